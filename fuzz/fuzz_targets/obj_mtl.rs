//! OBJ and MTL files: the input is `m.obj`, and what follows a `\n#MTL\n` marker is also
//! served as `m.mtl`. Loading must succeed or fail with an error; a loaded mesh must be
//! well formed, and its scene must build a valid BVH.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::obj_mtl);
});
