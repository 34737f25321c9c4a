//! Sphere congruences (Sec. 2): the central spheres of the reference surface (jet fit, Def. 2.9)
//! and the support structure of an ST mesh (node axes and planar support elements, Sec. 2.2).

pub mod central_spheres;
pub mod jet;
pub mod support_structure;
