//! Reading and writing meshes and point clouds: OBJ, PLY (ASCII and binary), OFF, glTF/GLB
//! and XYZ, chosen by file extension, and mesh animations as glTF morph targets (GLB).
//! Readers parse the whole file from one byte slice and never panic on malformed input;
//! writers are atomic (temporary file + rename). The apps print through [`print_stdout`], which
//! ends the process quietly when its reader has gone.

mod ascii_scan;
mod atomic_write;
mod format;
mod format_error;
mod glb_builder;
mod gltf;
mod gltf_buffers;
mod mesh_data;
mod mesh_files;
mod morph_animation;
mod obj;
mod off;
mod output_guard;
mod ply;
mod read_mesh;
mod read_point_cloud;
mod standard_output;
mod uri_decoding;
mod vertex_list;
mod write_mesh;
mod write_point_cloud;
mod xyz;

pub use atomic_write::{atomic_write, remove_temporaries_on_interrupt};
pub use format::MeshFormat;
pub use mesh_files::mesh_files_in;
pub use morph_animation::{
    MorphAnimation, morph_animation_glb_bytes, read_morph_animation, write_morph_animation,
};
pub use output_guard::OutputGuard;
pub use ply::PlyEncoding;
pub use read_mesh::{read_mesh, read_mesh_bytes};
pub use read_point_cloud::{read_point_cloud, read_point_cloud_bytes};
pub use standard_output::{BROKEN_PIPE_STATUS, print_stderr, print_stdout};
pub use vertex_list::{read_vertex_list, read_vertex_list_bytes};
pub use write_mesh::{write_mesh, write_ply};
pub use write_point_cloud::write_point_cloud;
