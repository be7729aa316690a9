//! Any bytes, read as a `.gltf` JSON file in a folder holding legitimate, escaping and
//! special files (see `meshgnn_fuzz::read_in_folder`), and from memory.
#![no_main]

use libfuzzer_sys::fuzz_target;
use meshgnn_fuzz::{read_bytes, read_in_folder};
use meshgnn_geometry::MeshFormat;

fuzz_target!(|bytes: &[u8]| {
    read_bytes(bytes, MeshFormat::Gltf);
    read_in_folder(bytes, "m.gltf");
});
