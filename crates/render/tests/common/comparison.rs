//! A comparison of two block estimates on the blocks a test selects: per block and channel,
//! plus the channel means pooled over those blocks, with the smallest detectable bias.

use super::{BlockEstimate, BlockView, detectable_bias};
use testkit::{ZTestOutcome, z_test_entries};

/// The entries of the blocks `keep` selects (3 per block), then the 3 channel means pooled over
/// those blocks (which see a bias common to the blocks far more sharply than one block does).
pub fn entries(estimate: &BlockEstimate, keep: &[bool]) -> (Vec<f64>, Vec<f64>) {
    let mut means = Vec::new();
    let mut errors = Vec::new();
    for (b, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        means.extend_from_slice(&estimate.means[b * 3..b * 3 + 3]);
        errors.extend_from_slice(&estimate.std_errors[b * 3..b * 3 + 3]);
    }
    let (pooled, pooled_errors) = estimate.pooled(keep);
    means.extend(pooled);
    errors.extend(pooled_errors);
    (means, errors)
}

/// One comparison of a test: its description, outcome, and the smallest relative bias of the
/// tested estimate the same test rejects.
pub struct Comparison {
    /// The description, with the blocks compared, the worst entry and the detectable bias.
    pub what: String,
    /// The Z-test over the blocks' entries and the pooled means.
    pub outcome: ZTestOutcome,
    /// The smallest relative bias of the tested estimate that the same test rejects.
    pub detectable: f64,
}

impl Comparison {
    /// Compares `a` with the reference `b` on the blocks of `views` that `keep` selects, at
    /// per-comparison level `alpha`; checks that the test has power (at least 16 blocks, a
    /// reference mean over the compared entries above `min_mean`, typical standard errors
    /// below a quarter of it).
    pub fn new(
        what: String,
        a: &BlockEstimate,
        b: &BlockEstimate,
        views: &[BlockView],
        keep: impl Fn(&BlockView) -> bool,
        alpha: f64,
        min_mean: f64,
    ) -> Self {
        let keep: Vec<bool> = views.iter().map(keep).collect();
        let blocks = keep.iter().filter(|k| **k).count();
        let (am, ae) = entries(a, &keep);
        let (bm, be) = entries(b, &keep);
        let outcome = z_test_entries(&am, &ae, &bm, &be, alpha);
        let detectable = detectable_bias(&am, &ae, &bm, &be, alpha);
        // Power: many blocks, bright enough that a few % error is many standard errors.
        assert!(blocks >= 16, "{what}: only {blocks} blocks compared");
        let mean = bm.iter().sum::<f64>() / bm.len() as f64;
        let error = (be.iter().chain(&ae).map(|e| e * e).sum::<f64>() / bm.len() as f64).sqrt();
        assert!(mean > min_mean && error < 0.25 * mean, "{what}: mean {mean}, typical error {error}");
        let worst_block = outcome.worst_index / 3;
        let worst = if worst_block < blocks {
            let block = keep.iter().enumerate().filter(|(_, k)| **k).nth(worst_block).unwrap().0;
            format!("block ({}, {})", block % a.blocks_x, block / a.blocks_x)
        } else {
            "the pooled mean".to_string()
        };
        let what = format!(
            "{what} ({blocks} blocks, worst: {worst} channel {}; detects a bias of {:.1} %)",
            outcome.worst_index % 3,
            100.0 * detectable
        );
        eprintln!("{what}: {outcome}");
        Self { what, outcome, detectable }
    }
}
