//! Scene files: any bytes, read as `fuzz.toml` from an in-memory file source, must load or
//! fail with an error; a loaded scene must be well formed and build a valid BVH.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::scene_file);
});
