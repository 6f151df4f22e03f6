//! Discrete distributions sampled by inverting their cumulative sum.

/// A distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    total: f32,
}

impl Distribution1D {
    /// Builds the distribution. Returns `None` when there are no weights, a weight is negative
    /// or not finite, or all are zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        if weights.is_empty() || weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len());
        let mut sum = 0.0f64;
        for w in weights {
            sum += *w as f64;
            cdf.push(sum as f32);
        }
        if sum <= 0.0 {
            return None;
        }
        Some(Self { cdf, total: sum as f32 })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    /// Always false: an empty distribution cannot be built.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Picks an index for the uniform number `u ∈ [0,1)`; returns it with its probability.
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let target = u * self.total;
        let index = self.cdf.partition_point(|c| *c <= target).min(self.cdf.len() - 1);
        (index, self.probability(index))
    }

    /// Probability of index `i`.
    pub fn probability(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]).unwrap();
        assert_eq!(d.sample(0.0).0, 0);
        assert_eq!(d.sample(0.2).0, 0);
        assert_eq!(d.sample(0.3).0, 2);
        assert_eq!(d.sample(0.999).0, 2);
        assert!((d.probability(2) - 0.75).abs() < 1e-6);
        assert_eq!(d.probability(1), 0.0);
        assert!(Distribution1D::new(&[0.0]).is_none());
        assert!(Distribution1D::new(&[f32::NAN]).is_none());
    }
}
