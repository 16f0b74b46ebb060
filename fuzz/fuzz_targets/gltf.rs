//! glTF files: the input is `fuzz.glb` (when it starts with the GLB magic) or `fuzz.gltf`,
//! beside a buffer `b.bin` and an image `t.png`; loading it as a bare scene must succeed or
//! fail with an error, and a loaded scene must be well formed and build a valid BVH.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::gltf);
});
