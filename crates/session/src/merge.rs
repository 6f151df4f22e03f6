//! `vcm merge`: the films of a render's slices ([`crate::slice`]), checked to be the N parts of
//! one render, added into the film one process would have accumulated. Fixed-point sums make
//! the addition exact, so the merged film is bit for bit the single-process film of the same
//! render with `--sums fixed` (and the image, variance image and checkpoint written from it).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use scene::{Film, FilmSums};

use crate::checkpoint::{self, Recorded, header_lines};

/// The merged render: its settings (without a slice) and its film of every iteration.
pub struct Merged {
    /// What the render recorded (the slices' common settings).
    pub recorded: Recorded,
    /// The film of iterations 0..n.
    pub film: Film,
}

/// Loads the slice checkpoints `parts` and merges them. Errors name the files: a checkpoint
/// that is not a slice, parts of different renders (the differing settings), a slice given
/// twice, a missing slice (with its iterations), an unfinished slice. Each part is added as it
/// is loaded (fixed-point sums add in any order), so the memory is one accumulated film and one
/// loaded part, whatever the number of slices.
pub fn merge(parts: &[PathBuf]) -> Result<Merged> {
    if parts.is_empty() {
        bail!("vcm merge needs the slice checkpoints (part-*.ckpt) of one render");
    }
    let mut slices: BTreeMap<u32, PathBuf> = BTreeMap::new();
    let mut common: Option<(PathBuf, Recorded)> = None;
    let mut total: Option<FilmSums> = None;
    let mut rejected = 0;
    for path in parts {
        let (recorded, film) = checkpoint::load(path)?;
        let Some(slice) = recorded.slice else {
            bail!("'{}' holds a whole render, not a slice (render slices with --slice K/N)", path.display());
        };
        let range = slice.range();
        if (film.first_iteration(), film.next_iteration()) != (range.start, range.end) {
            bail!(
                "'{}' holds iterations {}..{} of slice {}'s {}..{}: the slice is unfinished; complete it with `vcm \
                 render --resume {}`",
                path.display(),
                film.first_iteration(),
                film.next_iteration(),
                slice.name(),
                range.start,
                range.end,
                path.display()
            );
        }
        match &common {
            None => common = Some((path.clone(), recorded.clone())),
            Some((first_path, first)) => {
                let differences = differences(first, &recorded);
                if !differences.is_empty() {
                    bail!(
                        "'{}' and '{}' are not slices of one render: {}",
                        first_path.display(),
                        path.display(),
                        differences.join("; ")
                    );
                }
            }
        }
        if let Some(other) = slices.get(&slice.index) {
            bail!("slice {} is given twice: '{}' and '{}'", slice.name(), other.display(), path.display());
        }
        slices.insert(slice.index, path.clone());
        rejected += film.rejected_samples();
        match &mut total {
            None => total = Some(film.into_raw_sums()),
            Some(sums) => {
                sums.add(film.raw_sums()).map_err(|e| anyhow::anyhow!("cannot merge '{}': {e}", path.display()))?
            }
        }
    }
    let (_, mut recorded) = common.expect("at least one part");
    let slice = recorded.slice.expect("checked above");
    let missing: Vec<String> = (0..slice.count)
        .filter(|index| !slices.contains_key(index))
        .map(|index| {
            let range = crate::slice::Slice { index, ..slice }.range();
            format!("{index}/{} (iterations {}..{})", slice.count, range.start, range.end)
        })
        .collect();
    if !missing.is_empty() {
        bail!("slices missing: {} (the merge needs all {} slices)", missing.join(", "), slice.count);
    }
    // Every slice is present and complete, so the parts tile 0..n.
    let (width, height) = recorded.resolution;
    let sums = total.expect("at least one part");
    let film = Film::from_raw(width, height, sums, 0, slice.iterations, rejected)
        .ok_or_else(|| anyhow::anyhow!("internal error: merged sums of another size than {width}x{height}"))?;
    recorded.slice = None;
    Ok(Merged { recorded, film })
}

/// The settings in which two slice checkpoints differ (the slice index aside), as
/// `key: a vs b`.
fn differences(a: &Recorded, b: &Recorded) -> Vec<String> {
    let lines = |r: &Recorded| {
        let mut r = r.clone();
        if let (Some(slice), Some(first)) = (&mut r.slice, &a.slice) {
            slice.index = first.index;
        }
        header_lines(&r)
    };
    let (la, lb) = (lines(a), lines(b));
    let key = |line: &String| line.split_once('=').map_or(line.clone(), |(k, _)| k.to_string());
    let mut out = Vec::new();
    for line in la.iter().filter(|l| !lb.contains(l)) {
        let other = lb.iter().find(|l| key(l) == key(line)).map_or("(absent)".to_string(), |l| l.clone());
        out.push(format!("{line} vs {other}"));
    }
    for line in lb.iter().filter(|l| !la.contains(l) && !la.iter().any(|m| key(m) == key(l))) {
        out.push(format!("(absent) vs {line}"));
    }
    out
}

/// Writes the merged image (and the `.png` preview of a linear format, as `vcm render`
/// does), the variance image and a checkpoint of the merged render when asked for; returns
/// what was written, as the summary names it.
pub fn write(merged: &Merged, image: &Path, variance: Option<&Path>, checkpoint: Option<&Path>) -> Result<Vec<String>> {
    let film = &merged.film;
    let (width, height) = (film.width() as usize, film.height() as usize);
    let options = io::WriteOptions { exposure_stops: 0.0 };
    let mut written = Vec::new();
    for (path, _) in crate::outputs::output_paths(image)? {
        io::write_image(&path, &io::Image { width, height, pixels: film.mean() }, &options)?;
        written.push(path.display().to_string());
    }
    if let Some(path) = variance {
        let Some(pixels) = film.variance_of_mean() else {
            bail!("no variance image: the values are too large for the fixed-point sums of squares");
        };
        io::write_image(path, &io::Image { width, height, pixels }, &options)?;
        written.push(format!("variance {}", path.display()));
    }
    if let Some(path) = checkpoint {
        checkpoint::save(path, &merged.recorded, film)?;
        written.push(format!("checkpoint {}", path.display()));
    }
    Ok(written)
}
