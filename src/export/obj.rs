//! Wavefront OBJ writer, with objects and groups per kind:
//!
//! ```text
//! o panels
//! g panel_0        (one group per panel, named by its id = face index)
//! v … / f …
//! o support
//! g support
//! v … / f …
//! o node_axes
//! g node_axes
//! v … / l i j      (one line element per segment)
//! ```
//!
//! Indices are global and 1-based; every panel writes its own vertices (shared arc points are
//! repeated bit-identically, so importers that weld merge them). Coordinates use Rust's shortest
//! round-trip formatting of f64.

use std::fmt::Write;

use glam::DVec3;

use crate::congruence::support_structure::SupportGeometry;
use crate::panels::panel::Panel;

fn vertex(out: &mut String, p: DVec3) {
    let _ = writeln!(out, "v {} {} {}", p.x, p.y, p.z);
}

/// OBJ text of the panels, optional support triangles and optional node-axis segments.
pub fn write_obj(panels: &[Panel], support: Option<&SupportGeometry>, node_axes: Option<&[(DVec3, DVec3)]>) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# spherical-faces {}: {} panels", env!("CARGO_PKG_VERSION"), panels.len());
    let mut next = 1usize; // next vertex number
    let _ = writeln!(out, "o panels");
    for p in panels {
        let _ = writeln!(out, "g panel_{}", p.face);
        for &x in &p.positions {
            vertex(&mut out, x);
        }
        for t in &p.triangles {
            let _ = writeln!(out, "f {} {} {}", next + t[0] as usize, next + t[1] as usize, next + t[2] as usize);
        }
        next += p.positions.len();
    }
    if let Some(s) = support.filter(|s| !s.triangles.is_empty()) {
        let _ = writeln!(out, "o support");
        let _ = writeln!(out, "g support");
        for &x in &s.positions {
            vertex(&mut out, x);
        }
        for t in &s.triangles {
            let _ = writeln!(out, "f {} {} {}", next + t[0] as usize, next + t[1] as usize, next + t[2] as usize);
        }
        next += s.positions.len();
    }
    if let Some(axes) = node_axes.filter(|a| !a.is_empty()) {
        let _ = writeln!(out, "o node_axes");
        let _ = writeln!(out, "g node_axes");
        for &(a, b) in axes {
            vertex(&mut out, a);
            vertex(&mut out, b);
        }
        for i in 0..axes.len() {
            let _ = writeln!(out, "l {} {}", next + 2 * i, next + 2 * i + 1);
        }
    }
    out
}

/// OBJ text of a mesh of polygons itself (vertices and faces), for a designer's CAD tool.
pub fn write_mesh_obj(mesh: &crate::geometry::mesh::PolyMesh, name: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# spherical-faces {}: {} vertices, {} faces", env!("CARGO_PKG_VERSION"), mesh.vertex_count(), mesh.face_count());
    let _ = writeln!(out, "o {name}");
    for &p in &mesh.positions {
        vertex(&mut out, p);
    }
    for f in &mesh.faces {
        out.push('f');
        for &v in f.corners() {
            let _ = write!(out, " {}", v + 1);
        }
        out.push('\n');
    }
    out
}
