//! EXT_ and KHR_meshopt_compression: the input is a vertex and an index stream (after a
//! header choosing strides, filter and mode), served as a primitive's compressed buffer
//! views; loading it must succeed or fail with an error, and a loaded scene must be well
//! formed.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(init: meshtrace_fuzz::install_panic_hook(), |data: &[u8]| {
    meshtrace_fuzz::guarded(data, meshtrace_fuzz::meshopt);
});
