//! Spherical Faces: approximation of free-form surfaces by meshes with spherical faces.
//!
//! The layers, lowest first (`ARCHITECTURE.md` is the map; `tests/architecture.rs` keeps the
//! imports pointing down):

/// Benchmark workloads shared by `cargo bench` (divan) and the wasm bench in the browser.
pub mod bench_workloads;
/// Sphere congruences (Sec. 2): central spheres, node axes and support elements.
pub mod congruence;
/// Design links: the versioned URL fragment.
pub mod design_link;
/// Writers: GLB, OBJ, the panel schedule and the typed report.
pub mod export;
/// Generalized spheres, circles, the absolute sphere Ω, closest points, meshes.
pub mod geometry;
/// What a method promises of its result, measured: guarantees and the verdict of a run.
pub mod guarantees;
/// OBJ, glTF and GLB import with typed errors.
pub mod import;
/// Sphere meshes and their panels: arcs, gaps, tessellation, deviation.
pub mod panels;
/// Parameter ranges, checked once, and a method's parameters in a design link.
pub mod params;
/// The session, one method seam, its stages and the typed worker protocol.
pub mod pipeline;
/// Progress events, the typed `Cancelled` and the caller's clock, taken by every method.
pub mod progress;
/// The reference surface R with its cached derived data, and the glide terms.
pub mod reference;
/// Sizing fields from influence zones and pliant remeshing (Sec. 3); quad remeshing along a
/// cross field (Sec. 5.2).
pub mod remeshing;
/// A small deterministic random generator for tests and samples.
pub mod rng;
/// The built-in reference surfaces.
pub mod samples;
/// Sparse Levenberg–Marquardt on faer: residual terms, finite-difference checks, ordering.
pub mod solver;
/// Sec. 5: SQ meshes with support structure (5.1: the congruence and its torsal directions;
/// 5.2: the quad mesh, the final sphere optimization, panels and support structure).
pub mod sq;
/// Sec. 3: ST meshes with adapted face size (the angle-minimizing ST mesh).
pub mod st_adapted;
/// Sec. 4: ST meshes with support structure.
pub mod st_support;
/// Mean, median, percentiles and histograms of samples.
pub mod stats;
/// User-facing text: control characters escaped.
pub mod text;
/// Model units (m, cm, mm, ft, in) and lengths written with a unit.
pub mod units;
/// The browser app (wasm32 only): egui UI, wgpu viewer, the worker.
#[cfg(target_arch = "wasm32")]
pub mod web;
