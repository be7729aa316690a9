//! Analytic test shapes with known geometry: spheres, planes, cubes and tori at any resolution.
//! Tests compare operators against their closed-form answers on these, and the data
//! generators start from them.

mod cube;
mod grid;
mod icosphere;
mod torus;

pub use cube::subdivided_cube;
pub use grid::grid_plane;
pub use icosphere::icosphere;
pub use torus::torus;
