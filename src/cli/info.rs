//! `info`: what a surface is, as one JSON object (or the objects of a .3dm file).

use spherical_faces::congruence::central_spheres::JetParams;

use super::args::Input;
use super::files::load;
use super::outcome::Failure;
use super::rhino;

/// One JSON object: counts after triangulation and welding (of a B-spline: its tessellation),
/// and the mean curvature (jet-fitted on a mesh, exact on a B-spline, at the vertices); for a
/// B-spline also its degrees, control grid, domain and the ranges of H and K.
pub fn info(input: &Input, list_objects: bool) -> Result<String, Failure> {
    if list_objects {
        if !rhino::is_3dm(&input.surface) {
            return Err(Failure::input("--list-objects applies to .3dm files only"));
        }
        return rhino::list(&input.surface);
    }
    let loaded = load(input)?;
    let field = loaded.surface.curvature(&JetParams::default(), &mut |_| Ok(())).map_err(|_| Failure::input("cancelled"))?;
    let s = &loaded.info.stats;
    let c = &field.summary;
    let mut json = serde_json::json!({
        "vertices": s.vertices,
        "faces": s.faces,
        "boundary_loops": s.boundary_loops,
        "non_manifold_edges": s.non_manifold_edges,
        "bbox_diagonal": loaded.info.bbox_diagonal,
        "mean_curvature": {"min": c.min_h, "max": c.max_h, "mean": c.mean_h},
        "h_changes_sign": c.h_changes_sign,
    });
    if let Some(b) = &loaded.info.bspline {
        json["bspline"] = serde_json::json!({
            "degree": b.degree,
            "control_points": b.control,
            "domain": b.domain,
            "rational": b.rational,
            "tessellation": b.tessellation,
            "mean_curvature": {"min": b.mean_curvature[0], "max": b.mean_curvature[1]},
            "gauss_curvature": {"min": b.gauss_curvature[0], "max": b.gauss_curvature[1]},
        });
    }
    Ok(json.to_string())
}
