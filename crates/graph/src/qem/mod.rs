//! QEM edge-collapse decimation (Garland & Heckbert 1997) and what is built on it: the
//! decimation itself ([`decimate`], algorithm and guarantees in `decimation.rs`), the plane
//! quadrics it sums ([`Quadric`]), QEM vertex selection for point clouds on a mesh
//! ([`qem_vertices`], thesis ch. 5.5) and, for the neural mesh simplifier of ch. 6, the
//! selected vertices' regions with their quadrics ([`SeedRegions`]), the vertices moved to
//! their regions' best-fitting vertex ([`region_quadric_vertices`]), exchanged between
//! regions by quadric error ([`region_seed_exchange`]) and placed at their quadric optimum
//! ([`region_quadric_placement`]), and the QEM connectivity of chosen vertices
//! ([`kept_vertex_connectivity`]). The other files
//! are the decimation's parts: welding, vertex records and collapses, edge placement,
//! validity checks, candidate sorting, speculative parallel checks, memory warm-up, the
//! changed-vertex sets and the split of large meshes into blocks decimated at once.

mod candidates;
mod collapse_checks;
mod collapser;
mod decimation;
mod edge_placement;
mod held_vertex_folding;
mod kept_connectivity;
mod memory_warmup;
mod quadric;
mod region_placement;
mod seed_exchange;
mod seed_regions;
mod spatial_blocks;
mod speculation;
mod vertex_bits;
mod vertex_selection;
mod weld_by_position;

pub use decimation::{
    Decimation, DecimationOptions, StopReason, Target, decimate, decimate_keeping,
    decimate_with_progress,
};
pub use kept_connectivity::kept_vertex_connectivity;
pub use quadric::Quadric;
pub use region_placement::{region_quadric_placement, region_quadric_vertices};
pub use seed_exchange::region_seed_exchange;
pub use seed_regions::SeedRegions;
pub use vertex_selection::{QemVertices, qem_vertices};
pub use weld_by_position::{WeldedMesh, weld_coincident_vertices};
