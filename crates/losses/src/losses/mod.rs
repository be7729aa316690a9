//! Differentiable training losses on candle tensors (`f32` in production, `f64` in the
//! gradient tests). Shapes are stated on each function.

mod adaptive_chamfer;
mod chamfer_loss;
mod curvature_preservation;
mod edge_crossings;
mod edge_valence_excess;
mod face_penalty;
mod gradient_check;
mod mean_curvature_at_scale;
mod probabilistic_chamfer;
mod probabilistic_surface_distance;
mod reconstruction_l1;
mod simplification_objective;
mod temporal_coherence;
mod tensor_points;
mod triangle_collision;
mod triangle_overlap;

pub use adaptive_chamfer::{adaptive_chamfer, adaptive_chamfer_weights};
pub use chamfer_loss::chamfer_loss;
pub use curvature_preservation::curvature_preservation;
pub use edge_crossings::edge_crossings;
pub use edge_valence_excess::edge_valence_excess;
pub use gradient_check::{GradientDisagreement, gradient_disagreement};
pub use mean_curvature_at_scale::mean_curvature_at_scale;
pub use probabilistic_chamfer::probabilistic_chamfer;
pub use probabilistic_surface_distance::{
    ReverseSurfaceParams, probabilistic_surface_forward, probabilistic_surface_reverse,
};
pub use reconstruction_l1::reconstruction_l1;
pub use simplification_objective::{
    SimplificationTerms, SimplificationWeights, simplification_objective,
};
pub use temporal_coherence::temporal_coherence;
pub use triangle_collision::triangle_collision;
pub use triangle_overlap::triangle_overlap;

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Tensor};

    #[test]
    fn triangle_penalties_have_gradient_m_over_f() {
        // d L / d p_t = m(t) / F exactly; checked by central differences in the gradient test
        // helper on the collision loss of one stabbing pair plus a far face (m = 1, 1, 0).
        let v = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.5, 0.5, -1.0],
            [0.5, 0.5, 1.0],
            [3.0, 3.0, 0.5],
            [9.0, 9.0, 9.0],
            [10.0, 9.0, 9.0],
            [9.0, 10.0, 9.0],
        ];
        let f = [[0, 1, 2], [3, 4, 5], [6, 7, 8]];
        let p = Tensor::new(&[0.3f64, 0.6, 0.9], &Device::Cpu).unwrap();
        gradient_check::assert_gradient_matches(&p, |p| triangle_collision(&v, &f, p, 20), 1e-6);
        gradient_check::assert_gradient_matches(&p, |p| edge_crossings(&v, &f, p, 20), 1e-6);
        let var = candle_core::Var::from_tensor(&p).unwrap();
        let l = triangle_collision(&v, &f, var.as_tensor(), 20).unwrap();
        let g: Vec<f64> = l
            .backward()
            .unwrap()
            .get(var.as_tensor())
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(g, vec![1.0 / 3.0, 1.0 / 3.0, 0.0]);

        // overlap: two coplanar overlapping faces (m_o = 1 each) and the far face (0)
        let v2 = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.5, 0.5, 0.0],
            [2.5, 0.5, 0.0],
            [0.5, 2.5, 0.0],
            [9.0, 9.0, 9.0],
            [10.0, 9.0, 9.0],
            [9.0, 10.0, 9.0],
        ];
        let tol = crate::predicates::InsideTolerance::default();
        gradient_check::assert_gradient_matches(
            &p,
            |p| triangle_overlap(&v2, &f, p, 50, tol),
            1e-6,
        );
        let l = triangle_overlap(&v2, &f, &p, 50, tol).unwrap();
        assert!((l.to_scalar::<f64>().unwrap() - (0.3 + 0.6) / 3.0).abs() < 1e-12);
    }

    #[test]
    fn mesh_neighbours_cost_nothing_in_every_penalty() {
        let sphere = meshgnn_geometry::icosphere(2);
        let n = sphere.face_count();
        let p = Tensor::ones(n, candle_core::DType::F32, &Device::Cpu).unwrap();
        let v = sphere.vertices();
        let f = sphere.triangles();
        let tol = crate::predicates::InsideTolerance::default();
        for l in [
            triangle_collision(v, f, &p, 20).unwrap(),
            edge_crossings(v, f, &p, 20).unwrap(),
            triangle_overlap(v, f, &p, 50, tol).unwrap(),
        ] {
            assert_eq!(l.to_scalar::<f32>().unwrap(), 0.0);
        }
    }
}
