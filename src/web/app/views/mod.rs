//! One view per method, behind one trait, as egui's demo apps do: its controls and results in the
//! side panel, what it draws in the viewport, what its stages' snapshots, progress and summary
//! update, and what the automation state says of it. The side panel, the viewport and the reducer
//! go over [`views`] instead of matching methods; a new method adds one module here and one line
//! in [`views`].

pub mod curvature;
pub mod method_view;
pub mod sq;
pub mod st_adapted;
pub mod st_support;

pub use method_view::MethodView;

use crate::design_link::Design;

/// Every method's view, in the order of [`crate::design_link::Method::all`].
pub fn views(design: &Design) -> Vec<Box<dyn MethodView>> {
    vec![
        Box::new(curvature::CurvatureMethod),
        Box::new(st_adapted::StAdaptedMethod::new(design)),
        Box::new(st_support::StSupportMethod::new(design)),
        Box::new(sq::SqMethod::default()),
    ]
}
