//! Prints the SQ congruence figures (Sec. 5.1) before and after the optimization:
//! `cargo run --release --example sq_congruence -- [FILE.json|sample:vault ...]`.

use spherical_faces::pipeline::session::Loaded;
use spherical_faces::progress::Clock;
use spherical_faces::samples::Sample;
use spherical_faces::sq::params::{Inequality, SqParams};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        args = vec!["../shared/data/bsplines/tunnel_arch.json".into(), "sample:vault".into()];
    }
    let slack = std::env::var("SQ_SLACK").is_ok();
    for a in args {
        let loaded = match a.strip_prefix("sample:") {
            Some(k) => Loaded::from_sample(Sample::from_key(k).expect("a sample")),
            None => Loaded::from_file(&std::fs::read(&a).expect("readable"), &a).expect("loads"),
        };
        let mut params = SqParams { inequality: if slack { Inequality::Slack } else { Inequality::Hinge }, ..SqParams::default() };
        if let Some(m) = std::env::var("SQ_MARGIN_THETA").ok().and_then(|m| m.parse().ok()) {
            params.margins_deg[0] = m;
        }
        if let Some(m) = std::env::var("SQ_MARGIN_ALPHA").ok().and_then(|m| m.parse().ok()) {
            params.margins_deg[1] = m;
        }
        if let Some(w) = std::env::var("SQ_ORTH").ok().and_then(|m| m.parse().ok()) {
            params.torsal_weights.lc_orth = w;
        }
        let t0 = std::time::Instant::now();
        match spherical_faces::sq::compute_congruence(&loaded.surface, &params, Clock::native(), &mut |_| Ok(())) {
            Ok(r) => {
                println!("{a}: {:.0} ms, iterations {} + {}", t0.elapsed().as_secs_f64() * 1e3, r.lc_iterations, r.torsal_iterations);
                println!("  initial {:?}", r.initial_figures);
                println!("  final   {:?}", r.figures);
                println!(
                    "  E_LC/term after step 1 {:.3e}, after step 2 {:.3e}; radius fit error {:.3e}; lc it median {:?} ms, torsal it median {:?} ms",
                    r.lc_residual_step1,
                    r.lc_residual,
                    r.radius_fit_error,
                    r.lc_iteration_median_ms(),
                    r.torsal_iteration_median_ms()
                );
                for w in &r.warnings {
                    println!("  warning: {w}");
                }
            }
            Err(e) => println!("{a}: {e}"),
        }
    }
}
