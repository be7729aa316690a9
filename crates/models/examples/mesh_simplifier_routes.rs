//! Routes for training the neural mesh simplifier (docs/mesh_simplifier_model.md, "Training"):
//! how good the nearest-seed Voronoi-dual face targets are (their candidate recall, and the
//! dual mesh itself against QEM at the same face count) for the thesis' multinomial draw, the
//! balanced draw of the untrained sampler's probabilities and of the QEM importance, and FPS
//! picks.
//!
//! `train EPOCHS` trains the model ([`SimplifierTraining`]) on the train families and reports
//! the simplifications of the test families before and after; the best epoch's weights go to
//! `mesh_simplifier.safetensors`, the resumable state to `mesh_simplifier.checkpoint`. With
//! `VALENCE_WEIGHT` the loss adds that multiple of the edge-valence excess; with `FROM` the
//! training starts from those weights (a fine-tuning).
//! `eval WEIGHTS RES...` reports trained weights on the test families at each resolution.
//!
//! ```text
//! cargo run --release -p meshgnn-models --example mesh_simplifier_routes -- [RES] [RATIO]
//! cargo run --release -p meshgnn-models --example mesh_simplifier_routes -- train EPOCHS [RES] [LR] [PER_FAMILY] [VALENCE_WEIGHT] [FROM]
//! cargo run --release -p meshgnn-models --example mesh_simplifier_routes -- eval WEIGHTS RES...
//! cargo run --release -p meshgnn-models --example mesh_simplifier_routes -- ceiling WEIGHTS RATIO FILE...
//! ```

use candle_core::{DType, Device};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_data::{ShapeFamily, shape_mesh};
use meshgnn_geometry::{TriMesh, boundary_loops, nearest_seed_dual_triangles, sample_surface};
use meshgnn_graph::{
    DecimationOptions, FpsStart, Target, balanced_sampling, decimate, decimate_keeping,
    fast_farthest_point_sampling, qem_vertices, weighted_sampling,
};
use meshgnn_losses::metrics::{chamfer_distance, watertightness};
use meshgnn_models::Checkpoint;
use meshgnn_models::mesh_simplifier::{
    CANDIDATE_FEATURES, DualTargets, MeshInput, NeuralMeshSimplifier, NeuralMeshSimplifierConfig,
    NeuralSimplifyOptions, SimplifierExample, SimplifierTraining, candidate_features,
    qem_importance,
};
use meshgnn_models::training::{Trainable, TrainingConfig, train};

type AnyResult<T> = std::result::Result<T, Box<dyn std::error::Error + Send + Sync>>;

fn dual_mesh(mesh: &TriMesh, picks: &[u32]) -> AnyResult<TriMesh> {
    let faces = nearest_seed_dual_triangles(mesh, picks)?;
    let corners = picks.iter().map(|&i| mesh.vertices()[i as usize]).collect();
    Ok(TriMesh::new(corners, faces)?)
}

/// Symmetric mean squared Chamfer distance between 20 000 surface samples of each.
fn surface_chamfer(a: &TriMesh, b: &TriMesh) -> AnyResult<f64> {
    let pa = sample_surface(a, 20_000, 1)?.points;
    let pb = sample_surface(b, 20_000, 2)?.points;
    Ok(chamfer_distance(&pa, &pb)?.symmetric_mean())
}

/// Simplifies each test mesh to a tenth of its vertices; prints raw and final WA, the holes
/// left, WA and holes after closing those of at most 30 edges, and the Chamfer distance
/// against QEM's at the same face count, with the vertices placed and at their selected
/// positions.
fn report(
    model: &NeuralMeshSimplifier,
    test: &[(&str, TriMesh, f64)],
    label: &str,
) -> AnyResult<()> {
    for (name, mesh, cd_qem) in test {
        let started = std::time::Instant::now();
        let out = model.simplify(mesh, mesh.vertex_count() / 10, 1, &Default::default())?;
        let seconds = started.elapsed().as_secs_f64();
        let with_holes_filled = NeuralSimplifyOptions {
            fill_holes_up_to: Some(30),
            ..Default::default()
        };
        let keep_positions = NeuralSimplifyOptions {
            keep_positions: true,
            ..Default::default()
        };
        let selected = model
            .simplify(mesh, mesh.vertex_count() / 10, 1, &keep_positions)?
            .mesh;
        let filled = model
            .simplify(mesh, mesh.vertex_count() / 10, 1, &with_holes_filled)?
            .mesh;
        let cd = |simplified: &TriMesh| {
            if simplified.face_count() == 0 {
                Ok(f64::NAN)
            } else {
                surface_chamfer(mesh, simplified)
            }
        };
        println!(
            "{label} {name} ({} faces): raw {} faces WA_raw {:.2} -> {} faces WA {:.2} holes {} \
             (filled: WA {:.2} holes {}) CD/qem {:.2} (selected positions {:.2}) ({seconds:.2} s)",
            mesh.face_count(),
            out.raw_faces,
            out.wa_raw,
            out.mesh.face_count(),
            out.wa,
            out.holes,
            watertightness(&filled),
            boundary_loops(&filled).len(),
            cd(&out.mesh)? / cd_qem,
            cd(&selected)? / cd_qem,
        );
    }
    Ok(())
}

/// The test families' first shapes at `resolution`, with QEM's Chamfer distance at a tenth of
/// the vertices.
fn test_meshes(resolution: usize) -> AnyResult<Vec<(&'static str, TriMesh, f64)>> {
    let mut test = Vec::new();
    for family in ShapeFamily::ALL.iter().filter(|f| f.split() == "test") {
        let mesh = shape_mesh(*family, 1, resolution)?;
        let qem = decimate(
            &mesh,
            &DecimationOptions {
                target: Target::Faces(2 * (mesh.vertex_count() / 10)),
                ..Default::default()
            },
        )?;
        let cd_qem = surface_chamfer(&mesh, &qem.mesh)?;
        test.push((family.name(), mesh, cd_qem));
    }
    Ok(test)
}

/// `eval WEIGHTS [RES...]`: the report of trained weights on the test families.
fn evaluate(args: &[String]) -> AnyResult<()> {
    let weights = args.first().ok_or("give the weights file")?;
    let model = NeuralMeshSimplifier::load(weights)?;
    for resolution in args[1..].iter().map(|s| s.parse::<usize>()) {
        report(&model, &test_meshes(resolution?)?, weights)?;
    }
    Ok(())
}

/// `ceiling WEIGHTS RATIO FILE...`: on each mesh file, what the face classifier could reach
/// among the trained sampler's picks, beside what it reaches: their nearest-seed Voronoi dual
/// (the target it learnt); the dual triangles among the edge predictor's candidates (the raw
/// output of a classifier that never errs, with their recall); the trained classifier's raw
/// output (`p_t > 0.5`); the candidates a restricted-Delaunay rule on two of the classifier's
/// own input features keeps (empty circumsphere, normal agreement above 0.5); the QEM
/// connectivity of the picks (every other vertex collapsed onto them, [`decimate_keeping`]);
/// and for reference the dual of QEM's own vertex selection. Each as faces, WA and Chamfer
/// distance over QEM's at the same face count.
fn target_ceiling(args: &[String]) -> AnyResult<()> {
    let [weights, ratio, files @ ..] = args else {
        return Err("give the weights file, the vertex ratio and mesh files".into());
    };
    let model = NeuralMeshSimplifier::load(weights)?;
    let ratio: f64 = ratio.parse()?;
    println!(
        "file\tfaces\tpicks\tdual: faces WA CD/qem\tdual candidates (recall)\tclassifier\t\
         Delaunay rule\tpicks' QEM\tdual of QEM's picks"
    );
    for file in files {
        let mesh = meshgnn_geometry::read_mesh(file)?;
        let m = ((mesh.vertex_count() as f64) * ratio).round() as usize;
        let input = MeshInput::new(&mesh, model.device())?;
        let pass = model.forward(&input, m, 0)?;
        let picks = &pass.sampled.indices;
        let corners: Vec<[f32; 3]> = picks.iter().map(|&i| mesh.vertices()[i as usize]).collect();
        let candidates = &pass.candidates.triangles;
        let kept_candidates = |keep: &dyn Fn(usize) -> bool| {
            let faces = (0..candidates.len()).filter(|&i| keep(i));
            TriMesh::new(corners.clone(), faces.map(|i| candidates[i]).collect())
        };
        let labels: Vec<f32> = DualTargets::new(&pass)?.face_labels.to_vec1()?;
        let perfect_classifier = kept_candidates(&|i| labels[i] > 0.0)?;
        let probabilities: Vec<f32> = pass.face_probabilities.to_vec1()?;
        let classifier = kept_candidates(&|i| probabilities[i] > 0.5)?;
        let normals: Vec<[f32; 3]> = picks.iter().map(|&i| input.normals[i as usize]).collect();
        let features = candidate_features(&corners, &normals, candidates, &pass.dual)?;
        let feature = |i: usize, k: usize| features[i * CANDIDATE_FEATURES + k];
        let delaunay_rule = kept_candidates(&|i| feature(i, 4) > 0.0 && feature(i, 0) > 0.5)?;
        let dual = dual_mesh(&mesh, picks)?;
        // Faces, WA and CD over QEM's at the same face count; no distance without faces.
        let judged = |target: &TriMesh| -> AnyResult<String> {
            let faces = target.face_count();
            if faces == 0 {
                return Ok("0 - -".into());
            }
            let qem = decimate(
                &mesh,
                &DecimationOptions {
                    target: Target::Faces(faces),
                    ..Default::default()
                },
            )?;
            Ok(format!(
                "{faces} {:.1} {:.2}",
                watertightness(target),
                surface_chamfer(&mesh, target)? / surface_chamfer(&mesh, &qem.mesh)?
            ))
        };
        let collapsed = decimate_keeping(
            &mesh,
            &DecimationOptions {
                target: Target::Faces(1),
                keep_original_positions: true,
                ..Default::default()
            },
            picks,
            &mut |_| {},
        )?;
        // QEM's selection stops short on some meshes (non-manifold regions): no figure then.
        let qem_picks_dual = match qem_vertices(&mesh, m) {
            Ok(selection) => judged(&dual_mesh(&mesh, &selection.indices)?)?,
            Err(_) => "-".into(),
        };
        println!(
            "{file}\t{}\t{m}\t{}\t{} ({:.3})\t{}\t{}\t{} ({} vertices)\t{qem_picks_dual}",
            mesh.face_count(),
            judged(&dual)?,
            judged(&perfect_classifier)?,
            perfect_classifier.face_count() as f64 / dual.face_count().max(1) as f64,
            judged(&classifier)?,
            judged(&delaunay_rule)?,
            judged(&collapsed.mesh)?,
            collapsed.mesh.vertex_count()
        );
    }
    Ok(())
}

fn train_model(args: &[String]) -> AnyResult<()> {
    let epochs: usize = args.first().map_or(Ok(10), |s| s.parse())?;
    let resolution: usize = args.get(1).map_or(Ok(32), |s| s.parse())?;
    let learning_rate: f64 = args.get(2).map_or(Ok(1e-3), |s| s.parse())?;
    let per_family: u64 = args.get(3).map_or(Ok(6), |s| s.parse())?;
    let valence_weight: f64 = args.get(4).map_or(Ok(0.0), |s| s.parse())?;
    let mut train_set = Vec::new();
    let mut validation = Vec::new();
    for family in ShapeFamily::ALL.iter().filter(|f| f.split() == "train") {
        for seed in 0..=per_family {
            let example = SimplifierExample::new(shape_mesh(*family, 100 + seed, resolution)?)?;
            if seed == per_family {
                validation.push(example);
            } else {
                train_set.push(example);
            }
        }
    }
    let test = test_meshes(40)?;
    let mut task = SimplifierTraining::new(
        &NeuralMeshSimplifierConfig::default(),
        train_set,
        validation,
        (0.05, 0.25),
        0,
    )?
    .with_valence_weight(valence_weight);
    if let Some(weights) = args.get(5) {
        let path = std::path::Path::new(weights);
        task.restore(&Checkpoint::load(path)?, path)?;
    }
    report(task.model(), &test, "epoch 0")?;
    let config = TrainingConfig {
        epochs,
        batch_size: 1,
        learning_rate,
        lr_decay: 0.95,
        checkpoint: Some("mesh_simplifier.checkpoint".into()),
        best_weights: Some("mesh_simplifier.safetensors".into()),
        ..Default::default()
    };
    let started = std::time::Instant::now();
    train(&mut task, &config, &mut |p| {
        if p.epoch_end {
            println!(
                "epoch {}: loss {:.4} recall {:.3} validation {:.4} ({:.0} s)",
                p.epoch + 1,
                p.loss,
                p.figure.unwrap_or(f64::NAN),
                p.validation.unwrap_or(f64::NAN),
                started.elapsed().as_secs_f64()
            );
        }
    })?;
    report(task.model(), &test, &format!("epoch {epochs}"))?;
    Ok(())
}

fn main() -> AnyResult<()> {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("train") => return train_model(&args[2..]),
        Some("eval") => return evaluate(&args[2..]),
        Some("ceiling") => return target_ceiling(&args[2..]),
        _ => {}
    }
    let resolution: usize = args.get(1).map_or(Ok(40), |s| s.parse())?;
    let ratio: f64 = args.get(2).map_or(Ok(0.1), |s| s.parse())?;
    let map = VarMap::new();
    let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    let mut config = NeuralMeshSimplifierConfig::default();
    if let Some(k) = args.get(3) {
        config.edges.candidate_neighbours = k.parse()?;
    }
    let model = NeuralMeshSimplifier::new(vb, &config)?;
    meshgnn_models::spiral::seeded_initialization(&map, 0)?;
    println!("shape\tfaces\tpicks\tdual_faces\trecall\tWA_dual\tCD_dual/CD_qem");
    for family in ShapeFamily::ALL {
        let mesh = shape_mesh(family, 1, resolution)?;
        let m = ((mesh.vertex_count() as f64) * ratio).round() as usize;
        let qem = decimate(
            &mesh,
            &DecimationOptions {
                target: Target::Faces(2 * m),
                ..Default::default()
            },
        )?;
        let cd_qem = surface_chamfer(&mesh, &qem.mesh)?;
        let input = MeshInput::new(&mesh, &Device::Cpu)?;
        let pass = model.forward(&input, m, 3)?;
        let fps = fast_farthest_point_sampling(mesh.vertices(), m, FpsStart::Index(0))?;
        let probabilities: Vec<f32> = pass.sampled.probabilities.to_vec1()?;
        let importance = qem_importance(&mesh)?;
        let routes = [
            ("multinomial", weighted_sampling(&probabilities, m, 3)?),
            ("balanced", pass.sampled.indices.clone()),
            (
                "balanced-qem",
                balanced_sampling(mesh.vertices(), &importance, m, 3)?,
            ),
            ("fps", fps),
        ];
        for (name, picks) in routes {
            let dual = dual_mesh(&mesh, &picks)?;
            let recall = if name == "balanced" {
                let targets = DualTargets::new(&pass)?;
                format!(
                    "{:.3} of {}",
                    targets.candidate_hits as f64 / targets.dual_faces.max(1) as f64,
                    pass.candidates.triangles.len()
                )
            } else {
                "-".into()
            };
            let cd = surface_chamfer(&mesh, &dual)?;
            println!(
                "{}/{name}\t{}\t{m}\t{}\t{recall}\t{:.2}\t{:.2}",
                family.name(),
                mesh.face_count(),
                dual.face_count(),
                watertightness(&dual),
                cd / cd_qem
            );
        }
    }
    Ok(())
}
