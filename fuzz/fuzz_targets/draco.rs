//! KHR_draco_mesh_compression: the input is a Draco stream (after the vertex and index
//! counts), served as a primitive's compressed geometry; loading it must succeed or fail
//! with an error, and a loaded scene must be well formed.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::draco);
});
