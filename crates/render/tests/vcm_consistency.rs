//! Consistency of the VCM engine's algorithms with each other and with the path tracer on
//! the four reference scenes: per-block Z-tests with a Šidák correction, restricted to the
//! blocks each algorithm can render (cornell.md §3.9).

mod common;

use common::{block_estimate, block_views, select, settings};
use scene::cornell;
use testkit::z_test_entries;

#[test]
#[ignore]
fn explore() {
    let scene = cornell::build(273, 32, 32).unwrap();
    let views = block_views(&scene, 4);
    let reference = block_estimate(&scene, &settings("bpt", 100), 4000, 4);
    for (algorithm, iterations) in [("pt", 4000), ("lt", 4000), ("vcm", 2000)] {
        let estimate = block_estimate(&scene, &settings(algorithm, 1), iterations, 4);
        let keep = |v: &common::BlockView| algorithm != "lt" || (!v.specular && !v.emitter_or_background);
        let (a, ae) = select(&estimate, &views, keep);
        let (b, be) = select(&reference, &views, keep);
        let outcome = z_test_entries(&a, &ae, &b, &be, 1e-3);
        eprintln!("{algorithm}: {outcome}");
    }
}
