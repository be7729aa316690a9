//! What the fuzz targets share: reading bytes through every public reader, and a folder in
//! which a glTF file may name legitimate, escaping and special files.
//!
//! The folder (made once per process) is `root/inner/`, where the fuzzed file is written:
//!
//! - `tri.bin`, `sub/tri.bin`: a 44-byte triangle buffer (3 f32 positions, u16 indices 0 1 2);
//! - `link.bin` → `../secret.bin` and `up` → `root`: symlinks that leave the folder;
//! - `zero` → `/dev/zero`, `pipe.bin` (a FIFO, when `mkfifo` exists), `dir.bin/` (a folder).
//!
//! `root/secret.bin` is a valid triangle buffer whose coordinates are all [`SECRET`]: a mesh
//! that comes back with that value was read from outside the folder, which is a crash. A FIFO
//! that was opened blocks, which libFuzzer reports as a timeout.

// Fuzzing harness: a failed setup or a broken promise must abort the run loudly.
#![allow(clippy::expect_used, clippy::panic)]

use meshgnn_geometry::{
    MeshFormat, read_mesh, read_mesh_bytes, read_point_cloud, read_point_cloud_bytes,
};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The coordinate written only into the file outside the folder.
pub const SECRET: f32 = 31337.0;

/// Reads `bytes` as `format` through both byte-level readers; errors are expected.
pub fn read_bytes(bytes: &[u8], format: MeshFormat) {
    let _ = read_mesh_bytes(bytes, format);
    let _ = read_point_cloud_bytes(bytes, format);
}

/// Writes `bytes` to `name` in the prepared folder and reads it as a mesh and a point cloud;
/// panics if anything from outside the folder came back.
pub fn read_in_folder(bytes: &[u8], name: &str) {
    let path = folder().join(name);
    std::fs::write(&path, bytes).expect("writing the fuzzed file");
    if let Ok(mesh) = read_mesh(&path) {
        check_no_secret(mesh.vertices());
    }
    if let Ok(cloud) = read_point_cloud(&path) {
        check_no_secret(cloud.points());
    }
}

fn check_no_secret(points: &[[f32; 3]]) {
    if points.iter().flatten().any(|&x| x == SECRET) {
        panic!("a buffer outside the glTF file's folder was read");
    }
}

/// A triangle buffer with every coordinate `x` (or 0 0 0, 1 0 0, 0 1 0 when `None`).
fn triangle_bin(x: Option<f32>) -> Vec<u8> {
    let mut bytes = Vec::new();
    let points = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    for p in points {
        p.iter()
            .for_each(|&c| bytes.extend(x.unwrap_or(c).to_le_bytes()));
    }
    [0u16, 1, 2]
        .iter()
        .for_each(|i| bytes.extend(i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes
}

fn folder() -> &'static Path {
    static FOLDER: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, inner) = FOLDER.get_or_init(|| {
        let root = tempfile::tempdir().expect("temporary folder");
        let inner = root.path().join("inner");
        std::fs::create_dir_all(inner.join("sub")).expect("creating the folder");
        std::fs::create_dir(inner.join("dir.bin")).expect("creating a folder");
        std::fs::write(root.path().join("secret.bin"), triangle_bin(Some(SECRET)))
            .expect("writing the secret");
        std::fs::write(inner.join("tri.bin"), triangle_bin(None)).expect("writing tri.bin");
        std::fs::write(inner.join("sub").join("tri.bin"), triangle_bin(None))
            .expect("writing sub/tri.bin");
        #[cfg(unix)]
        {
            use std::os::unix::fs::symlink;
            symlink(root.path().join("secret.bin"), inner.join("link.bin")).expect("symlink");
            symlink(root.path(), inner.join("up")).expect("symlink");
            symlink("/dev/zero", inner.join("zero")).expect("symlink");
            // Without mkfifo the FIFO case is simply not exercised.
            let _ = std::process::Command::new("mkfifo")
                .arg(inner.join("pipe.bin"))
                .status();
        }
        (root, inner)
    });
    inner
}
