//! Sphere congruences (Sec. 2): the central spheres of the reference surface (jet fit, Def. 2.9),
//! the support structure of an ST mesh (node axes and planar support elements, Sec. 2.2), the
//! associated line congruence of a congruence tangent to a surface (Sec. 2.1) and its discrete
//! torsal directions (Sec. 2.3, 5.1).

pub mod central_spheres;
pub mod jet;
pub mod line_congruence;
pub mod support_structure;
pub mod torsal;
