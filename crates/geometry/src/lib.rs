//! # meshgnn-geometry
//!
//! Triangle meshes and point clouds for the rest of meshgnn: the [`TriMesh`] and
//! [`PointCloud`] types, reading and writing OBJ, PLY, OFF, glTF/GLB and XYZ (and mesh
//! animations as glTF morph targets, [`MorphAnimation`]), and the geometric operators the
//! thesis builds on (normals, curvature of eq. 5.1-5.3, graph and cotangent Laplacians of
//! eq. 2.13-2.14, Laplacian eigenvectors, surface sampling, normalisation and validity
//! checks). One operation per module, named after what it computes.
//!
//! # Conventions
//! - Positions are stored as `[f32; 3]`; numerically sensitive code accumulates in `f64`.
//! - Triangles are counter-clockwise seen from outside; indices are `u32`.
//! - Laplacians are positive semi-definite: `L = D − W`.
//! - Every fallible function returns [`Error`], which names the file, element and problem.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod error;
mod io;
mod point_cloud;
mod primitives;
mod radix_heap;
mod row_chunked_products;
mod sparse_cholesky;
mod tri_mesh;
pub mod vec3;

mod boundary_loops;
mod bounding_box;
mod cap_flips;
mod component_seed_floor;
mod connected_components;
mod connected_regions;
mod convex_hull;
mod cotangent_laplacian;
mod count_bounds;
mod crack_closing;
mod curvature_at_scale;
mod curvature_features;
mod curvature_neighbourhoods;
mod degenerate_faces;
mod duplicate_faces;
mod edge_topology;
mod face_normals;
mod fold_flips;
mod graph_laplacian;
mod hole_filling;
mod input_content;
mod laplacian_eigenvectors;
mod lone_face_closing;
mod manifold;
mod manifold_face_selection;
mod mass_matrix;
mod mesh_report;
mod non_manifold_edges;
mod normalization;
mod overlays;
mod pca_normals;
mod pinch_bridges;
mod small_part_hulls;
mod spatial_index;
mod surface_sampling;
mod symmetric_eigen3;
mod tangent_chart_triangulation;
mod vertex_neighbours;
mod vertex_normals;
mod voronoi_dual;
mod watertight;

pub use error::{Error, Result};
/// The faer version whose sparse and dense matrices this crate returns.
pub use faer;
pub use io::{
    BROKEN_PIPE_STATUS, MeshFormat, MorphAnimation, OutputGuard, PlyEncoding, atomic_write,
    mesh_files_in, morph_animation_glb_bytes, print_stderr, print_stdout, read_mesh,
    read_mesh_bytes, read_morph_animation, read_point_cloud, read_point_cloud_bytes,
    read_vertex_list, read_vertex_list_bytes, remove_temporaries_on_interrupt, write_mesh,
    write_morph_animation, write_ply, write_point_cloud,
};
pub use point_cloud::PointCloud;
pub use primitives::{grid_plane, icosphere, subdivided_cube, torus};
pub use tri_mesh::TriMesh;

pub use boundary_loops::{boundary_loops, on_border};
pub use bounding_box::{bounding_box, bounding_box_diagonal};
pub use cap_flips::{CAP_RELATIVE_HEIGHT, flip_caps};
pub use component_seed_floor::{MIN_COMPONENT_SEEDS, component_seed_floor};
pub use connected_components::{UNREFERENCED, connected_components};
pub use connected_regions::{connected_nearest_seed_regions, island_seeds};
pub use convex_hull::convex_hull;
pub use cotangent_laplacian::cotangent_laplacian;
pub use count_bounds::{MAX_SURFACE_SAMPLES, check_count};
pub use crack_closing::close_cracks;
pub use curvature_at_scale::{
    CurvatureAtScale, MAX_SCALE_NEIGHBOURS, VOID_NEIGHBOURS, curvature_at_scale,
    kernel_neighbourhood,
};
pub use curvature_features::{CurvatureFeatures, curvature_features, curvature_features_with_h};
pub use curvature_neighbourhoods::curvature_neighbourhoods;
pub use degenerate_faces::degenerate_faces;
pub use duplicate_faces::duplicate_faces;
pub use edge_topology::{EdgeIncidence, EdgeTopology, edge_topology};
pub use face_normals::{face_areas, face_normals};
pub use fold_flips::flip_folds;
pub use graph_laplacian::{
    combinatorial_laplacian, combinatorial_laplacian_of_mesh, normalized_laplacian,
    normalized_laplacian_of_mesh,
};
pub use hole_filling::{MAX_FILLED_HOLE_EDGES, fill_holes, fill_holes_partly, fill_holes_where};
pub use input_content::{
    InputUse, MAX_COORDINATE_MAGNITUDE, check_input_mesh, check_input_points, read_input_mesh,
    read_input_point_cloud,
};
pub use laplacian_eigenvectors::{LaplacianEigenpairs, laplacian_eigenvectors};
pub use lone_face_closing::{LONE_FACE_REACH, MIN_LONE_FACE_DEPTH, close_lone_faces};
pub use manifold::{is_edge_manifold, is_vertex_manifold, non_manifold_vertices};
pub use manifold_face_selection::select_manifold_faces;
pub use mass_matrix::lumped_mass_matrix;
pub use mesh_report::{MeshReport, mesh_report};
pub use non_manifold_edges::{non_manifold_edges, non_watertight_edge_percentage};
pub use normalization::{Normalization, unit_sphere_normalization};
pub use overlays::{MAX_OVERLAY_FACES, remove_flaps, remove_overlays};
pub use pca_normals::{PcaFeatures, pca_normals_and_curvature};
pub use pinch_bridges::{BRIDGE_CANDIDATES, MAX_BRIDGES_PER_VERTEX, bridge_pinched_vertices};
pub use small_part_hulls::{
    MAX_HULL_AREA_RATIO, OpenPart, PartSurface, hull_small_open_parts, part_hull,
    rebuild_small_open_parts,
};
pub use spatial_index::{
    DEFAULT_LEAF_SIZE, Neighbours, SpatialIndex, SpatialNode, box_squared_distance,
    squared_distance,
};
pub use surface_sampling::{SurfaceSamples, sample_surface};
pub use symmetric_eigen3::symmetric_eigen3;
pub use tangent_chart_triangulation::{
    Reconstruction, TangentChartOptions, tangent_chart_triangulation,
};
pub use vertex_normals::vertex_normals;
pub use voronoi_dual::{
    geodesic_voronoi_regions, nearest_seed_dual_triangles, nearest_seed_regions, seed_of_vertex,
    voronoi_dual_edges, voronoi_dual_triangles,
};
pub use watertight::is_watertight;
