//! Moulds before and after the ST method's mould rounds (`st_adapted::moulds::fewer_moulds`) on
//! shared meshes, at 2 mm on a 30 m diagonal: per round the coarsening, moulds, largest kink and
//! distance.
//!
//! `cargo run --release --example fewer_moulds -- ../shared/data/meshes/tri_mesh.obj ...`

use spherical_faces::import::import_mesh;
use spherical_faces::panels::moulds::{Fabrication, MouldFits, MouldTarget};
use spherical_faces::progress::Clock;
use spherical_faces::reference::Reference;
use spherical_faces::remeshing::Sizing;
use spherical_faces::st_adapted::moulds::fewer_moulds;
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::units::{Length, Units};

fn main() {
    for path in std::env::args().skip(1) {
        let bytes = std::fs::read(&path).expect("readable");
        let reference = Reference::from_triangles(import_mesh(&bytes, &path).expect("a mesh").mesh);
        let diag = reference.diagonal();
        let fabrication = Fabrication { units: Units::M, moulds: MouldTarget::Tolerance(Length { value: diag * 2e-3 / 30.0, unit: None }) };
        let params = StAdaptedParams { sizing: Sizing::Adaptive { epsilon: 2e-3 }, fabrication, ..Default::default() };
        let result = spherical_faces::st_adapted::compute(&reference, &params, Clock::default(), &mut |_| Ok(())).unwrap();
        let before = fabrication.assign(&MouldFits::of(&result.panels), diag).moulds.len();
        let t = std::time::Instant::now();
        let fewer =
            fewer_moulds(&reference, &result.sphere_mesh, &result.metrics, &result.panels, &fabrication, &params, Clock::default(), &mut |_| Ok(()))
                .unwrap();
        println!(
            "{path}: {} panels, moulds {before}, kink max {:.2}°, distance {:.2e}; rounds in {:.0} ms:",
            result.panels.len(),
            result.metrics.max_kink_angle_deg,
            result.metrics.max_distance_to_reference,
            t.elapsed().as_secs_f64() * 1e3
        );
        match fewer {
            Some(f) => f.rounds.iter().for_each(|r| println!("  {r:?}")),
            None => println!("  no round kept fewer moulds"),
        }
    }
}
