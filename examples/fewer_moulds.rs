//! Moulds before and after the ST method's mould rounds (`st_adapted::moulds::fewer_moulds_of`) on
//! shared meshes, at 2 mm on a 30 m diagonal: per round the coarsening, moulds, largest kink and
//! distance.
//!
//! `cargo run --release --example fewer_moulds -- ../shared/data/meshes/tri_mesh.obj ...`

use spherical_faces::import::import_mesh;
use spherical_faces::panels::moulds::{Fabrication, MouldFits, MouldTarget};
use spherical_faces::progress::{Clock, Timings};
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::st_adapted::moulds::{fewer_moulds_of, Moved};
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::units::{Length, Units};

fn main() {
    for path in std::env::args().skip(1) {
        let bytes = std::fs::read(&path).expect("readable");
        let reference = Reference::from_triangles(import_mesh(&bytes, &path).expect("a mesh").mesh);
        let diag = reference.diagonal();
        let fabrication = Fabrication { units: Units::M, moulds: MouldTarget::Tolerance(Length { value: diag * 2e-3 / 30.0, unit: None }) };
        let params = StAdaptedParams { sizing: Sizing::Adaptive { epsilon: 2e-3 }, ..Default::default() };
        let result = spherical_faces::st_adapted::compute(&reference, &params, &Fabrication::default(), Clock::default(), &mut |_| Ok(())).unwrap();
        let before = fabrication.assign(&MouldFits::of(&result.panels), diag).moulds.len();
        let t = std::time::Instant::now();
        let start = Moved { sphere_mesh: result.sphere_mesh, panels: result.panels, deviations: result.panel_deviations, metrics: result.metrics };
        let (moved, outcome) =
            fewer_moulds_of(&reference, start.clone(), &params, &fabrication, Clock::default(), &mut Timings::start(Clock::default()), &mut |_| {
                Ok(())
            })
            .unwrap();
        println!(
            "{path}: {} panels, moulds {before}, kink max {:.2}°, distance {:.2e}; rounds in {:.0} ms:",
            start.panels.len(),
            start.metrics.max_kink_angle_deg,
            start.metrics.max_distance_to_reference,
            t.elapsed().as_secs_f64() * 1e3
        );
        outcome.rounds.iter().for_each(|r| println!("  {r:?}"));
        println!("  moulds after: {}", fabrication.assign(&MouldFits::of(&moved.panels), diag).moulds.len());
    }
}
