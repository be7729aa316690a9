//! Geometric predicates for the triangle losses of thesis eq. 6.11-6.13, evaluated in `f64`
//! with Shewchuk's forward error bound so that a sign is never a rounding artefact.

mod edge_crossing_count;
mod orient3d;
mod point_in_triangle;
mod segment_triangle;
mod segments_cross;
mod triangle_lattice;
mod triangles_intersect;
mod triangles_meet;
mod triangles_overlap;

pub use edge_crossing_count::edge_crossing_count;
pub use point_in_triangle::{InsideTolerance, point_in_triangle};
pub use segment_triangle::segment_crosses_triangle;
pub use segments_cross::segments_cross;
#[cfg(feature = "candle")]
pub(crate) use triangle_lattice::barycentric_point;
pub use triangle_lattice::triangle_lattice;
pub use triangles_intersect::triangles_intersect;
pub use triangles_meet::triangles_meet;
pub use triangles_overlap::triangles_overlap;

#[cfg(test)]
mod tests {
    use super::*;

    const T: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]];

    fn all_counts(t: &[[f32; 3]; 3], u: &[[f32; 3]; 3]) -> (bool, usize, bool) {
        let lattice = triangle_lattice(10);
        let tol = InsideTolerance::default();
        (
            triangles_intersect(t, u),
            edge_crossing_count(t, u),
            triangles_overlap(t, u, &lattice, tol) || triangles_overlap(u, t, &lattice, tol),
        )
    }

    #[test]
    fn two_crossing_triangles() {
        // u stands vertically in x = 0.5 and cuts through the interior of t along
        // y ∈ [0.5, 0.875]; no edge of u meets an edge of t.
        let u = [[0.5, 0.25, -1.0], [0.5, 0.75, 1.0], [0.5, 1.0, -1.0]];
        let (hit, crossings, overlap) = all_counts(&T, &u);
        assert!(hit);
        assert_eq!(crossings, 0); // not coplanar
        assert!(!overlap);
    }

    #[test]
    fn two_coplanar_overlapping() {
        let u = [[0.5, 0.5, 0.0], [2.5, 0.5, 0.0], [0.5, 2.5, 0.0]];
        let (hit, crossings, overlap) = all_counts(&T, &u);
        assert!(!hit);
        assert_eq!(crossings, 2);
        assert!(overlap);
        // a parallel copy slightly above still overlaps thanks to the normal tolerance
        let lifted = T.map(|p| [p[0] + 0.3, p[1] + 0.3, 1e-4]);
        assert!(all_counts(&T, &lifted).2);
    }

    #[test]
    fn two_disjoint() {
        let u = [[5.0, 5.0, 0.0], [6.0, 5.0, 0.0], [5.0, 6.0, 1.0]];
        assert_eq!(all_counts(&T, &u), (false, 0, false));
        let above = T.map(|p| [p[0], p[1], 1.0]);
        assert_eq!(all_counts(&T, &above), (false, 0, false));
    }

    #[test]
    fn shared_edge_neighbours_do_not_count() {
        // flat continuation across the hypotenuse
        let flat = [[2.0, 0.0, 0.0], [2.0, 2.0, 0.0], [0.0, 2.0, 0.0]];
        assert_eq!(all_counts(&T, &flat), (false, 0, false));
        // folded neighbour (dihedral angle < 180°)
        let folded = [[2.0, 0.0, 0.0], [1.5, 1.5, 1.0], [0.0, 2.0, 0.0]];
        assert_eq!(all_counts(&T, &folded), (false, 0, false));
        // neighbour sharing only a vertex
        let fan = [[0.0, 0.0, 0.0], [-1.0, 0.0, 0.5], [0.0, -1.0, 0.5]];
        assert_eq!(all_counts(&T, &fan), (false, 0, false));
    }
}
