//! Design links: round trips, links written before the methods were renamed in code, notices
//! for unknown and invalid fields, and file names as data.

use spherical_faces::congruence::central_spheres::JetParams;
use spherical_faces::design_link::*;
use spherical_faces::panels::edge_arcs::EdgeArcs;
use spherical_faces::pipeline::protocol::{MethodId, MethodParams, StageRequest};
use spherical_faces::pipeline::stages::{sq::SqStage, st_adapted::StAdaptedStage, st_support::StSupportStage};
use spherical_faces::remeshing::Sizing;
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::{RadiusStart, SqParams};
use spherical_faces::st_adapted::params::StAdaptedParams;
use spherical_faces::st_support::StSupportParams;

#[test]
fn round_trip() {
    let d = Design {
        reference: DesignSurface::Sample(Sample::TorusPatch),
        method: Method::Curvature,
        jet: JetParams { degree: 2, max_rings: 3, ..JetParams::default() },
        color: ColorBy::K1,
        shading: Shading::Flat,
        edges: true,
        camera: Some(CameraState { yaw: 0.5, pitch: -0.25, distance: 6.0, target: [1.0, -2.0, 0.125] }),
        ..Design::default()
    };
    let (back, notices) = Design::from_fragment(&d.to_fragment());
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(back, d);
    // The jet is held once: the methods' copies stay at their defaults and the stages get it.
    assert_eq!(back.params::<StAdaptedStage>().jet, JetParams::default());
    for stage in (Design { method: Method::Of(MethodId::StAdapted), ..back.clone() }).stage_requests() {
        match stage {
            StageRequest::Curvature(jet) => assert_eq!(jet, d.jet),
            StageRequest::Method(r) => assert_eq!(r.jet, d.jet),
        }
    }
}

#[test]
fn st_support_parameters_round_trip() {
    let d = Design::of::<StSupportStage>(StSupportParams {
        optimize_radius: true,
        support_depth: 0.035,
        axis_length: 0.25,
        radius_tolerance: 0.002,
        remesh: Sizing::Adaptive { epsilon: 2.5e-4 },
        max_distance: 0.004,
        ..StSupportParams::default()
    });
    assert!(d.to_fragment().contains("&max_dist=4e-3"), "{}", d.to_fragment());
    let (back, notices) = Design::from_fragment(&d.to_fragment());
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(back, d);
    let (bad, notices) = Design::from_fragment("#v=1&method=st-support&depth=-1&opt_r=2&rtol=nan&max_dist=2");
    assert_eq!(*bad.params::<StSupportStage>(), StSupportParams::default());
    assert_eq!(notices.len(), 4);
    assert!(!Design::default().to_fragment().contains("max_dist"), "the default bound is left out");
}

#[test]
fn st_adapted_parameters_round_trip() {
    for (sizing, variant) in [
        (Sizing::Adaptive { epsilon: 1.25e-3 }, EdgeArcs::BisectingPlanes),
        (Sizing::UniformFaces(2000), EdgeArcs::Intersection),
        (Sizing::None, EdgeArcs::Intersection),
    ] {
        let d = Design { color: ColorBy::Sizing, ..Design::of::<StAdaptedStage>(StAdaptedParams { sizing, variant, ..StAdaptedParams::default() }) };
        let frag = d.to_fragment();
        let (back, notices) = Design::from_fragment(&frag);
        assert!(notices.is_empty(), "{notices:?}");
        assert_eq!(back, d, "{frag}");
    }
    // ε and N go to the method the link names, wherever they stand in it.
    let (d, _) = Design::from_fragment("#v=1&eps=0.002&faces=50&method=st");
    assert_eq!(d.params::<StAdaptedStage>().sizing, Sizing::Adaptive { epsilon: 0.002 });
    assert_eq!(d.params::<StSupportStage>().remesh, StSupportParams::default().remesh);
    let (d, _) = Design::from_fragment("#v=1&eps=0.002&faces=50&method=st&sizing=faces");
    assert_eq!(d.params::<StAdaptedStage>().sizing, Sizing::UniformFaces(50));
    let (bad, notices) = Design::from_fragment("#v=1&method=st&eps=2&faces=3&variant=c&sizing=cubic");
    assert_eq!(*bad.params::<StAdaptedStage>(), StAdaptedParams::default());
    assert_eq!(notices.len(), 4, "{notices:?}");
}

/// Links written before the methods were renamed in code open the same designs.
#[test]
fn old_links_open_the_same_designs() {
    let (d, notices) = Design::from_fragment(
        "#v=1&sample=dome&method=st&jet_degree=3&jet_rings=4&sizing=adaptive&eps=4e-4&faces=600&variant=a&color=sizing&shading=smooth&edges=0",
    );
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(d.method, Method::Of(MethodId::StAdapted));
    assert_eq!(d.params::<StAdaptedStage>().sizing, Sizing::Adaptive { epsilon: 4e-4 });
    assert_eq!(d.params::<StAdaptedStage>().variant, EdgeArcs::Intersection);
    assert_eq!(d.color, ColorBy::Sizing);
    let (d, notices) = Design::from_fragment("#v=1&sample=dome&method=st&sizing=faces&faces=2000&variant=b");
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(d.params::<StAdaptedStage>().sizing, Sizing::UniformFaces(2000));
    assert_eq!(d.params::<StAdaptedStage>().variant, EdgeArcs::BisectingPlanes);
    let (d, notices) = Design::from_fragment(
        "#v=1&sample=torus&method=st-support&jet_degree=3&jet_rings=4&opt_r=1&depth=0.03&axis=0.2&rtol=0.002&remesh=faces&eps=4e-4&faces=300&color=H&shading=reflective&edges=1&cam=0.5,0.3,6,0,0,0",
    );
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(d.reference, DesignSurface::Sample(Sample::TorusPatch));
    assert_eq!(d.method, Method::Of(MethodId::StSupport));
    let st = d.params::<StSupportStage>();
    assert!(st.optimize_radius && st.support_depth == 0.03 && st.axis_length == 0.2 && st.radius_tolerance == 0.002);
    assert_eq!(st.remesh, Sizing::UniformFaces(300));
    assert!(d.camera.is_some() && d.edges);
    // The README's links.
    for link in [
        "#v=1&sample=dome&method=st&color=sizing",
        "#v=1&sample=dome&method=st-support&shading=reflective",
        "#v=1&sample=torus&color=k1&shading=flat&jet_degree=2&cam=0.5,0.3,6,0,0,0",
    ] {
        let (_, notices) = Design::from_fragment(link);
        assert!(notices.is_empty(), "{link}: {notices:?}");
    }
}

#[test]
fn unknown_and_invalid_fields_are_reported() {
    let (d, notices) = Design::from_fragment("#v=1&sample=torus&bogus=7&color=purple&jet_degree=9&cam=1,2");
    assert_eq!(d.reference, DesignSurface::Sample(Sample::TorusPatch));
    assert_eq!(d.color, ColorBy::MeanCurvature);
    assert_eq!(d.jet.degree, JetParams::default().degree);
    assert_eq!(d.camera, None);
    assert_eq!(notices.len(), 4, "{notices:?}");
    assert!(notices[0].contains("bogus"));
}

#[test]
fn an_unknown_sample_lists_the_samples() {
    let (d, notices) = Design::from_fragment("#v=1&sample=cathedral");
    assert_eq!(d.reference, Design::default().reference);
    assert_eq!(notices.len(), 1, "{notices:?}");
    for s in Sample::ALL {
        assert!(notices[0].contains(s.key()), "{notices:?}");
    }
    assert!(notices[0].contains("cathedral"));
}

#[test]
fn file_names_are_data() {
    let d = Design { reference: DesignSurface::OwnFile("<img src=x onerror=alert(1)>.obj".into()), ..Design::default() };
    let frag = d.to_fragment();
    assert!(!frag.contains('<') && !frag.contains(' '));
    let (back, notices) = Design::from_fragment(&frag);
    assert_eq!(back.reference, d.reference);
    // The app asks for the file in its view, not in a notice.
    assert!(notices.is_empty(), "{notices:?}");
}

#[test]
fn empty_and_garbage_fragments_give_defaults() {
    assert_eq!(Design::from_fragment("").0, Design::default());
    assert_eq!(Design::from_fragment("#").0, Design::default());
    let (d, n) = Design::from_fragment("#%%%&&==&v=1&%zz=1");
    assert_eq!(d, Design::default());
    assert!(!n.is_empty());
}

#[test]
fn sq_parameters_round_trip() {
    let d = Design {
        reference: DesignSurface::Sample(Sample::Vault),
        ..Design::of::<SqStage>(SqParams {
            theta_deg: 17.5,
            alpha_deg: 80.0,
            grid: 24,
            recompute_every: 5,
            max_distance: 0.02,
            ..SqParams::default()
        })
    };
    let fragment = d.to_fragment();
    assert!(fragment.contains("&method=sq&") && fragment.contains("&theta=17.5&alpha=80&grid=24&rs=5"), "{fragment}");
    assert!(fragment.contains("&max_dist=0.02"), "{fragment}");
    let (back, notices) = Design::from_fragment(&fragment);
    assert!(notices.is_empty(), "{notices:?}");
    assert_eq!(back, d);
    assert!(matches!(back.stage_requests().last(), Some(StageRequest::Method(r)) if r.params == MethodParams::Sq(d.params::<SqStage>().clone())));
    assert!(!fragment.contains("start="), "the default start is left out: {fragment}");
    let mut constant = d.clone();
    constant.params_mut::<SqStage>().start = RadiusStart::Constant;
    let fragment = constant.to_fragment();
    assert!(fragment.contains("&start=constant"), "{fragment}");
    assert_eq!(Design::from_fragment(&fragment).0, constant);
    let (bad, notices) = Design::from_fragment("#v=1&sample=vault&method=sq&theta=95&alpha=0&grid=2&rs=x&start=1/H");
    assert_eq!(*bad.params::<SqStage>(), SqParams::default());
    assert_eq!(notices.len(), 5, "{notices:?}");
}

/// Units and moulds round-trip, are held once in the design and reach every panel method's
/// stage; the defaults add nothing to the link.
#[test]
fn units_and_moulds_round_trip() {
    use spherical_faces::panels::moulds::{Fabrication, MouldTarget};
    use spherical_faces::units::{Length, Units};
    assert!(!Design::default().to_fragment().contains("units") && !Design::default().to_fragment().contains("mould"));
    for fabrication in [
        Fabrication { units: Units::Mm, moulds: MouldTarget::Tolerance(Length::new(0.5, Units::In)) },
        Fabrication { units: Units::Ft, moulds: MouldTarget::Count(8) },
        Fabrication { units: Units::Cm, moulds: MouldTarget::Tolerance(Length { value: 0.25, unit: None }) },
    ] {
        for method in MethodId::ALL.iter().map(|&m| Method::Of(m)) {
            let d = Design { method, fabrication, ..Design::default() };
            let (back, notices) = Design::from_fragment(&d.to_fragment());
            assert!(notices.is_empty(), "{notices:?}");
            assert_eq!(back, d, "{}", d.to_fragment());
            let got: Vec<Fabrication> = back
                .stage_requests()
                .into_iter()
                .filter_map(|s| match s {
                    StageRequest::Method(r) => Some(r.fabrication),
                    StageRequest::Curvature(_) => None,
                })
                .collect();
            assert_eq!(got, vec![fabrication]);
        }
    }
    let (d, notices) = Design::from_fragment("#v=1&units=furlong&moulds=0&mould_tol=-2mm");
    assert_eq!(d.fabrication, Fabrication::default());
    assert_eq!(notices.len(), 3, "{notices:?}");
}

/// Every parameter that defines a design, each away from its default, reads back from the link
/// (the main controls and the advanced ones of every method).
#[test]
fn every_design_parameter_round_trips() {
    use spherical_faces::sq::params::{RadiusBasis, Until};
    let sq = {
        let mut p = SqParams {
            theta_deg: 12.5,
            alpha_deg: 81.0,
            grid: 17,
            recompute_every: 7,
            faces: 333,
            until: Until::Remesh,
            start: RadiusStart::Central,
            support_depth: 0.0125,
            axis_length: 0.07,
            radius_tolerance: 2e-4,
            lc_iterations: 77,
            torsal_iterations: 88,
            final_iterations: 9,
            radius_basis: RadiusBasis { degree: 3, controls: 8 },
            optimize_moulds: true,
            max_distance: 0.005,
            ..SqParams::default()
        };
        p.sphere_iterations[1] = 123;
        p.lc_weights.lc = 1.5;
        p.lc_weights.lc_orth = 2.5;
        p.torsal_weights =
            spherical_faces::sq::params::TorsalWeights { lc: 0.5, lc_orth: 0.7, torsal: 1.1, angle: 2.2, fair: 0.3, reg: 0.04, ..p.torsal_weights };
        let w = &mut p.sphere_weights;
        (w.sphere, w.supp, w.torsal_plane, w.prox_f, w.prox_c, w.fair) = (2.5, 0.6, 0.02, 1.2, 0.3, 0.25);
        p
    };
    let st_support = StSupportParams {
        optimize_radius: true,
        support_depth: 0.03,
        axis_length: 0.2,
        radius_tolerance: 0.002,
        remesh: Sizing::UniformFaces(1234),
        optimize_moulds: true,
        max_distance: 0.003,
        ..StSupportParams::default()
    };
    let st_adapted = StAdaptedParams {
        sizing: Sizing::Adaptive { epsilon: 3e-4 },
        variant: EdgeArcs::BisectingPlanes,
        optimize_moulds: true,
        radius_tolerance: 5e-4,
        ..StAdaptedParams::default()
    };
    let designs = [Design::of::<SqStage>(sq), Design::of::<StSupportStage>(st_support), Design::of::<StAdaptedStage>(st_adapted)];
    for d in designs {
        let fragment = d.to_fragment();
        let (back, notices) = Design::from_fragment(&fragment);
        assert!(notices.is_empty(), "{fragment}: {notices:?}");
        assert_eq!(back, d, "{fragment}");
        // Each parameter is checked where it is read: the method's own check agrees.
        let Method::Of(m) = d.method else { unreachable!() };
        match back.method_params(m) {
            MethodParams::Sq(p) => p.check().unwrap(),
            MethodParams::StSupport(p) => p.check().unwrap(),
            MethodParams::StAdapted(p) => p.check().unwrap(),
        }
    }
}
