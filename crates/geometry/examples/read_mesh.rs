//! Reads a mesh file and prints its size and the time the read took (the number the I/O
//! speed comparison in `docs/io.md` uses).
//!
//! Run: `cargo run --release -p meshgnn-geometry --example read_mesh -- FILE`
//! Prints one line: `vertices V faces F seconds S`.

use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: read_mesh FILE");
        return ExitCode::FAILURE;
    };
    let start = std::time::Instant::now();
    match meshgnn_geometry::read_mesh(&path) {
        Ok(mesh) => {
            let seconds = start.elapsed().as_secs_f64();
            println!(
                "vertices {} faces {} seconds {seconds:.6}",
                mesh.vertex_count(),
                mesh.face_count()
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}
