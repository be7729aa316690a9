//! Any bytes, read as OBJ (mesh and point cloud): errors are fine, a panic or an
//! allocation past libFuzzer's memory limit is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;
use meshgnn_fuzz::read_bytes;
use meshgnn_geometry::MeshFormat;

fuzz_target!(|bytes: &[u8]| read_bytes(bytes, MeshFormat::Obj));
