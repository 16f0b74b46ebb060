//! KHR_texture_basisu: the input is a KTX2 file, served as the image of a textured
//! triangle's base colour; loading it must succeed or fail with an error, and a loaded
//! scene must be well formed.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::ktx2);
});
