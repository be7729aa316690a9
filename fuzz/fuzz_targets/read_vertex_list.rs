//! Any bytes, read as a vertex index list (`meshsimplify simplify --keep`): errors are fine, a
//! panic or an allocation past libFuzzer's memory limit is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|bytes: &[u8]| {
    let _ = meshgnn_geometry::read_vertex_list_bytes(bytes);
});
