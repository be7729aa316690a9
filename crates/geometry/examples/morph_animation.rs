//! Writes a small morph-target animation GLB: an icosphere (subdivision 2, 162 vertices) that
//! breathes and sways over 24 frames at 24 fps, one second that loops. Used by
//! `tools/gltf-validate/check.sh` to run the Khronos glTF-Validator on real writer output; the
//! file also plays in any glTF viewer.
//!
//! Run: `cargo run -p meshgnn-geometry --example morph_animation -- OUT.glb`
//! Prints one line: `wrote OUT.glb: F frames of V vertices at R fps, B bytes`.

use meshgnn_geometry::{MorphAnimation, icosphere, write_morph_animation};
use std::f32::consts::TAU;
use std::process::ExitCode;

/// Frames in the loop.
const FRAMES: usize = 24;
/// Frames per second.
const FPS: f64 = 24.0;

fn main() -> ExitCode {
    let Some(path) = std::env::args_os().nth(1) else {
        eprintln!("usage: morph_animation OUT.glb");
        return ExitCode::FAILURE;
    };
    let sphere = icosphere(2);
    let frames: Vec<Vec<[f32; 3]>> = (0..FRAMES)
        .map(|k| {
            let phase = TAU * k as f32 / FRAMES as f32;
            sphere
                .vertices()
                .iter()
                .map(|p| {
                    let breath = 1.0 + 0.15 * phase.sin();
                    let sway = 0.2 * p[1] * phase.cos();
                    [p[0] * breath + sway, p[1] * breath, p[2] * breath]
                })
                .collect()
        })
        .collect();
    let vertices = sphere.vertex_count();
    let written = MorphAnimation::new(sphere, frames, FPS)
        .and_then(|animation| write_morph_animation(&path, &animation));
    if let Err(error) = written {
        eprintln!("error: {error}");
        return ExitCode::FAILURE;
    }
    let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
    println!(
        "wrote {}: {FRAMES} frames of {vertices} vertices at {FPS} fps, {bytes} bytes",
        path.to_string_lossy()
    );
    ExitCode::SUCCESS
}
