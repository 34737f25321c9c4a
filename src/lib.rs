//! Spherical Faces: approximation of free-form surfaces by meshes with spherical faces.
//!
//! Layers, one direction:
//! - pure geometry and numerics ([`mesh`], [`import`], [`sphere`], [`curvature`], [`samples`]),
//! - the pipeline and its worker protocol ([`pipeline`], [`design_link`]),
//! - the browser app ([`web`], wasm32 only), which consumes snapshots.

pub mod curvature;
pub mod design_link;
pub mod import;
pub mod mesh;
pub mod pipeline;
pub mod remesh;
pub mod rng;
pub mod solver;
pub mod samples;
pub mod sphere;
pub mod sphere_mesh;
pub mod panels;
pub mod export;
pub mod absolute_sphere;
/// Benchmark workloads shared by `cargo bench` (divan) and the wasm bench in the browser.
pub mod bench_workloads;
pub mod st_support;
pub mod st_angle;

#[cfg(target_arch = "wasm32")]
pub mod web;
