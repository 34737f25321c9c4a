//! The associated line congruence of a sphere congruence tangent to a surface (Sec. 2.1):
//! spheres with centres c = f + r n (Eq. 1) and radii r; the line L through f parallel to
//! c_u × c_v (it is orthogonal to the centre surface's tangent plane, Fig. 3), with
//! c_u = f_u + r_u n + r n_u and c_v = f_v + r_v n + r n_v.

// Negated float comparisons are deliberate: they also reject NaN.

use glam::DVec3;

use crate::geometry::bspline::SurfaceFrame;

/// The centre surface's derivatives at one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CentreDerivatives {
    pub c: DVec3,
    pub cu: DVec3,
    pub cv: DVec3,
}

/// c, c_u and c_v of the congruence with radius (r, r_u, r_v) at a surface frame.
pub(crate) fn centre_derivatives(frame: &SurfaceFrame, (r, ru, rv): (f64, f64, f64)) -> CentreDerivatives {
    let n = frame.normal;
    CentreDerivatives { c: frame.point + r * n, cu: frame.su + ru * n + r * frame.nu, cv: frame.sv + rv * n + r * frame.nv }
}

/// Below this |c_u × c_v| / (|f_u| |f_v|) the centre surface is singular and the line is
/// undefined (e.g. the central spheres of a sphere patch all coincide).
pub const SINGULAR_CENTRE_SURFACE: f64 = 1e-9;

impl CentreDerivatives {
    /// The unit direction of the associated line, on the side of `normal`; None where the
    /// centre surface is singular ([`SINGULAR_CENTRE_SURFACE`], relative to the surface's
    /// own |f_u| |f_v| = `scale`).
    pub fn line(&self, normal: DVec3, scale: f64) -> Option<DVec3> {
        let l = self.cu.cross(self.cv);
        let len = l.length();
        if !(len > SINGULAR_CENTRE_SURFACE * scale) {
            return None;
        }
        let l = l / len;
        Some(if l.dot(normal) < 0.0 { -l } else { l })
    }
}
