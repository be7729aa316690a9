//! Any bytes, read as GLB from memory (where external URIs are refused) and as a `.glb` in a
//! folder holding legitimate, escaping and special files (see `meshgnn_fuzz::read_in_folder`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use meshgnn_fuzz::{read_bytes, read_in_folder};
use meshgnn_geometry::MeshFormat;

fuzz_target!(|bytes: &[u8]| {
    read_bytes(bytes, MeshFormat::Glb);
    read_in_folder(bytes, "m.glb");
});
