//! `vcm merge`: translates its arguments for [`session::merge`] and prints what it wrote.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

/// Arguments of `vcm merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The checkpoints of the slices (`vcm render --slice K/N --checkpoint part-K.ckpt`), in
    /// any order: every slice of the render exactly once.
    #[arg(required = true, value_name = "PART")]
    parts: Vec<PathBuf>,
    /// The merged image; the format follows the extension (.exr, .pfm, .hdr, .png). A linear
    /// output also gets a .png preview beside it.
    #[arg(long, short, value_name = "FILE", default_value = "render.exr")]
    output: PathBuf,
    /// Also write the per-pixel variance of the mean to FILE (.exr, .pfm or .hdr).
    #[arg(long, value_name = "FILE")]
    variance: Option<PathBuf>,
    /// Also write the merged render as a checkpoint, which `vcm render --resume` continues
    /// (equal, byte for byte, to the checkpoint of the same render in one process).
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
}

/// Runs `vcm merge`.
pub fn run(args: MergeArgs) -> Result<()> {
    let merged = session::merge::merge(&args.parts)?;
    let written = session::merge::write(&merged, &args.output, args.variance.as_deref(), args.checkpoint.as_deref())?;
    let r = &merged.recorded;
    eprintln!(
        "merged {} slices: {} at {}x{}, {} iterations, {} rejected samples -> {}",
        args.parts.len(),
        r.algorithm,
        r.resolution.0,
        r.resolution.1,
        merged.film.iterations(),
        merged.film.rejected_samples(),
        written.join(", ")
    );
    Ok(())
}
