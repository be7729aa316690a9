//! # meshgnn-graph
//!
//! The classical graph operators every meshgnn model stands on, usable on their own: sparse
//! matrices, k-NN and mesh-adjacency graphs, k-rings and spiral sequences (thesis eq.
//! 2.27-2.28), QEM edge-collapse decimation (Garland & Heckbert 1997) with the pooling
//! matrices of a mesh hierarchy, farthest point sampling, and weighted sampling without
//! replacement. One operator per module, named after what it computes.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod closest_face;
mod closest_point_on_triangle;
mod error;
mod mesh_hierarchy;
mod pooling_matrices;
mod qem;

mod balanced_sampling;
mod candidate_triangles;
mod centroidal_relaxation;
mod csr_matrix;
mod farthest_point_sampling;
mod fast_farthest_point_sampling;
mod hilbert_order;
mod k_ring;
mod knn_graph;
mod mesh_adjacency;
mod radius_graph;
mod spiral;
mod systematic_sampling;
mod top_curvature_sampling;
mod triangle_knn_graph;
mod weighted_sampling;

pub use closest_face::{ClosestFace, FacePoint};
pub use error::{Error, Result};
pub use mesh_hierarchy::{HierarchyOptions, MeshHierarchy, build_hierarchy};
pub use pooling_matrices::{Downsampling, PoolingMatrices, Upsampling, pooling_matrices};
pub use qem::{
    Decimation, DecimationOptions, QemVertices, Quadric, SeedRegions, StopReason, Target,
    WeldedMesh, decimate, decimate_keeping, decimate_with_progress, kept_vertex_connectivity,
    qem_vertices, region_quadric_placement, region_quadric_vertices, region_seed_exchange,
    weld_coincident_vertices,
};

pub use balanced_sampling::balanced_sampling;
pub use candidate_triangles::candidate_triangles;
pub use centroidal_relaxation::{centroidal_relaxation, centroidal_relaxation_indexed};
pub use csr_matrix::CsrMatrix;
pub use farthest_point_sampling::{
    FpsStart, farthest_point_sampling, farthest_point_sampling_batch,
};
pub use fast_farthest_point_sampling::{
    fast_farthest_point_sampling, fast_farthest_point_sampling_batch,
    fast_farthest_point_sampling_indexed, fast_farthest_point_sampling_with_owners,
};
pub use hilbert_order::hilbert_order;
pub use k_ring::{k_disk, k_rings};
pub use knn_graph::{Neighbours, knn_graph, knn_query};
pub use mesh_adjacency::{adjacency_from_edges, vertex_adjacency, vertex_face_incidence};
pub use radius_graph::{RadiusNeighbours, radius_graph};
pub use spiral::{Spirals, spiral_sequences};
pub use systematic_sampling::systematic_sampling;
pub use top_curvature_sampling::top_curvature_sampling;
pub use triangle_knn_graph::{triangle_barycentres, triangle_knn_graph};
pub use weighted_sampling::{uniform_sampling, weighted_sampling};
