//! Slices of a render for batch schedulers without MPI (Slurm job arrays, Kubernetes Indexed
//! Jobs): `vcm render ... --slice K/N --checkpoint part-K.ckpt` renders the K-th of N
//! contiguous blocks of the render's iterations into a film with fixed-point sums
//! ([`scene::Summation::Fixed`]); [`crate::merge`] adds the N films into the film one process
//! would have accumulated, bit for bit. Design: `docs/distributed.md`.

use anyhow::{Result, bail};

/// Slice `index` of `count` of a render of `iterations` iterations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slice {
    /// 0-based index of the slice, below `count`.
    pub index: u32,
    /// Number of slices.
    pub count: u32,
    /// Iterations of the whole render.
    pub iterations: u64,
}

/// A slice as the command line gives it (`K/N`), before the render's iteration count is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SliceSpec {
    /// 0-based index of the slice.
    pub index: u32,
    /// Number of slices.
    pub count: u32,
}

impl SliceSpec {
    /// `K/N` as the command line spells it.
    pub fn name(&self) -> String {
        format!("{}/{}", self.index, self.count)
    }

    /// Parses `K/N` with 0 ≤ K < N.
    pub fn parse(text: &str) -> Result<Self> {
        let parsed = text.split_once('/').and_then(|(k, n)| Some((k.trim().parse().ok()?, n.trim().parse().ok()?)));
        match parsed {
            Some((index, count)) if index < count => Ok(Self { index, count }),
            Some((index, count)) => {
                bail!("--slice {index}/{count}: the index must be below the slice count (0..{count})")
            }
            None => bail!("--slice '{text}': expected K/N, e.g. 0/4 for the first of four slices"),
        }
    }

    /// The slice of a render of `iterations` iterations; an error when there are fewer
    /// iterations than slices.
    pub fn of(self, iterations: u64) -> Result<Slice> {
        if iterations < u64::from(self.count) {
            bail!(
                "--slice {}/{}: {iterations} iterations cannot be split into {} slices",
                self.index,
                self.count,
                self.count
            );
        }
        Ok(Slice { index: self.index, count: self.count, iterations })
    }
}

impl Slice {
    /// The global iterations of this slice, `start..end`: slice K of N holds
    /// ⌊K·n/N⌋..⌊(K+1)·n/N⌋, so the slices tile 0..n in order.
    pub fn range(&self) -> std::ops::Range<u64> {
        let bound = |k: u64| (u128::from(k) * u128::from(self.iterations) / u128::from(self.count)) as u64;
        bound(u64::from(self.index))..bound(u64::from(self.index) + 1)
    }

    /// `K/N` as the command line spells it.
    pub fn name(&self) -> String {
        SliceSpec { index: self.index, count: self.count }.name()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_tile_the_iterations_in_order() {
        for (iterations, count) in [(7u64, 3u32), (64, 4), (5, 5), (1000, 7)] {
            let mut next = 0;
            for index in 0..count {
                let range = Slice { index, count, iterations }.range();
                assert_eq!(range.start, next, "{iterations} in {count}");
                assert!(range.end > range.start);
                next = range.end;
            }
            assert_eq!(next, iterations);
        }
    }

    #[test]
    fn bad_slices_are_clear_errors() {
        assert_eq!(SliceSpec::parse("2/4").unwrap(), SliceSpec { index: 2, count: 4 });
        assert!(SliceSpec::parse("4/4").unwrap_err().to_string().contains("below the slice count"));
        assert!(SliceSpec::parse("x").unwrap_err().to_string().contains("expected K/N"));
        assert!(SliceSpec { index: 0, count: 8 }.of(4).unwrap_err().to_string().contains("cannot be split"));
    }
}
