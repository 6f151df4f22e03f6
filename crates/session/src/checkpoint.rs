//! Checkpoint files: everything needed to continue a progressive render exactly where it
//! stopped — the render's settings, the film's per-pixel sums (f64) and its iteration and
//! rejected-sample counts. The random streams are keyed by (seed, iteration, path), and the
//! radius schedule by the iteration index, so a resumed render equals an uninterrupted one.
//!
//! Format (version 3): the line `vcm-checkpoint 3`, then `key=value` lines, an empty line, the
//! sums and then the sums of squares, as little-endian f64 triples, row-major. Files are
//! written to `FILE.tmp` and renamed over `FILE`, so a crash never leaves a truncated
//! checkpoint.
//!
//! Version 3 added what the checkpoint rendered: `vcm_version` (the crate version of the
//! binary that wrote it; a different version may render differently, so it must match),
//! `scene_hash` and one `scene_read=HASH PATH` line per file the scene loader read
//! ([`Fingerprint`]). Version 2 files (no scene record) are refused with a message: resume
//! them with the binary that wrote them.

use render::path_tracer::{Heuristic, RussianRoulette};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use scene::Film;

use crate::fingerprint::Fingerprint;

/// The settings a checkpoint records (as the command line spells them).
#[derive(Clone, Debug, PartialEq)]
pub struct Recorded {
    /// Cornell scene mask (built-in scenes).
    pub mask: u32,
    /// Scene file (instead of the mask) and its `-D` parameters.
    pub scene_file: Option<(PathBuf, Vec<String>)>,
    /// Algorithm name.
    pub algorithm: String,
    /// Image width and height.
    pub resolution: (u32, u32),
    /// Maximum path length.
    pub max_length: u32,
    /// Seed.
    pub seed: u64,
    /// Radius factor.
    pub radius_factor: f32,
    /// Radius alpha.
    pub radius_alpha: f32,
    /// `global`, `fixed` or `per-pixel`.
    pub radius_mode: String,
    /// Memory-efficient mode.
    pub memory_efficient: bool,
    /// Spectral mode (absent in checkpoints written before it existed: RGB).
    pub spectral: bool,
    /// Russian roulette of the path tracer.
    pub russian_roulette: RussianRoulette,
    /// MIS heuristic of the path tracer.
    pub heuristic: Heuristic,
    /// Film mode, `fis` or `splat` (absent in checkpoints written before it existed: `fis`).
    pub film: String,
    /// What the scene was built from.
    pub fingerprint: Fingerprint,
}

/// The checkpoint format this binary reads and writes.
pub const FORMAT: u32 = 3;
const MAGIC: &str = "vcm-checkpoint 3";
/// The renderer version recorded in (and required of) checkpoints.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Writes `film` and `recorded` to `path` atomically (write, then rename).
pub fn save(path: &Path, recorded: &Recorded, film: &Film) -> Result<()> {
    if !film.has_variance() {
        bail!("internal error: a checkpoint needs a film that keeps its sums of squares");
    }
    let temporary = PathBuf::from(format!("{}.tmp", path.display()));
    let write = || -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(std::fs::File::create(&temporary)?);
        writeln!(out, "{MAGIC}")?;
        let r = recorded;
        writeln!(out, "vcm_version={VERSION}")?;
        writeln!(out, "scene_hash={:016x}", r.fingerprint.hash)?;
        for (file, hash) in &r.fingerprint.files {
            writeln!(out, "scene_read={hash:016x} {}", file.display())?;
        }
        writeln!(out, "mask={}", r.mask)?;
        if let Some((file, defines)) = &r.scene_file {
            writeln!(out, "scene_file={}", file.display())?;
            for define in defines {
                writeln!(out, "define={define}")?;
            }
        }
        writeln!(out, "algorithm={}", r.algorithm)?;
        writeln!(out, "resolution={}x{}", r.resolution.0, r.resolution.1)?;
        writeln!(out, "max_length={}", r.max_length)?;
        writeln!(out, "seed={}", r.seed)?;
        writeln!(out, "radius_factor={}", r.radius_factor)?;
        writeln!(out, "radius_alpha={}", r.radius_alpha)?;
        writeln!(out, "radius_mode={}", r.radius_mode)?;
        writeln!(out, "memory_efficient={}", r.memory_efficient)?;
        writeln!(out, "spectral={}", r.spectral)?;
        writeln!(out, "russian_roulette={}", r.russian_roulette.name())?;
        writeln!(out, "heuristic={}", r.heuristic.name())?;
        writeln!(out, "film={}", r.film)?;
        writeln!(out, "iterations={}", film.iterations())?;
        writeln!(out, "rejected={}", film.rejected_samples())?;
        writeln!(out)?;
        for pixel in film.sums().iter().chain(film.sum_squares()) {
            for value in pixel {
                out.write_all(&value.to_le_bytes())?;
            }
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()
    };
    write().with_context(|| format!("cannot write checkpoint '{}'", temporary.display()))?;
    std::fs::rename(&temporary, path)
        .with_context(|| format!("cannot move checkpoint '{}' to '{}'", temporary.display(), path.display()))
}

/// Reads a checkpoint: its settings and its film.
pub fn load(path: &Path) -> Result<(Recorded, Film)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read checkpoint '{}'", path.display()))?;
    let bad = |what: String| anyhow::anyhow!("'{}' is not a valid vcm checkpoint: {what}", path.display());
    let split = bytes.windows(2).position(|w| w == b"\n\n").ok_or_else(|| bad("no end of header".into()))?;
    let header = std::str::from_utf8(&bytes[..split]).map_err(|_| bad("the header is not text".into()))?;
    let mut lines = header.lines();
    match lines.next() {
        Some(MAGIC) => {}
        Some(old @ ("vcm-checkpoint 1" | "vcm-checkpoint 2")) => bail!(
            "checkpoint '{}' has format {} ('{old}'), which does not record the scene it rendered; this is vcm \
             {VERSION}, which reads format {FORMAT}: resume it with the vcm that wrote it, or start a new render",
            path.display(),
            &old[15..]
        ),
        _ => bail!(bad(format!("the first line is not '{MAGIC}'"))),
    }
    let mut fields = BTreeMap::new();
    let mut defines = Vec::new();
    let mut files = Vec::new();
    for (number, line) in lines.enumerate() {
        let (key, value) =
            line.split_once('=').ok_or_else(|| bad(format!("line {}: expected key=value", number + 2)))?;
        if key == "define" {
            defines.push(value.to_string());
        } else if key == "scene_read" {
            let (hash, file) = value
                .split_once(' ')
                .and_then(|(h, f)| Some((u64::from_str_radix(h, 16).ok()?, PathBuf::from(f))))
                .ok_or_else(|| bad(format!("line {}: expected scene_read=HASH PATH", number + 2)))?;
            files.push((file, hash));
        } else {
            fields.insert(key, value);
        }
    }
    fn field<T: std::str::FromStr>(fields: &BTreeMap<&str, &str>, key: &str) -> Option<T> {
        fields.get(key)?.parse().ok()
    }
    let missing = |key: &str| bad(format!("missing or invalid '{key}'"));
    let written_by: String = field(&fields, "vcm_version").ok_or_else(|| missing("vcm_version"))?;
    if written_by != VERSION {
        bail!(
            "checkpoint '{}' was written by vcm {written_by} (checkpoint format {FORMAT}); this is vcm {VERSION} \
             (format {FORMAT}), which may render differently: resume it with vcm {written_by}, or start a new render",
            path.display()
        );
    }
    let scene_hash =
        fields.get("scene_hash").and_then(|h| u64::from_str_radix(h, 16).ok()).ok_or_else(|| missing("scene_hash"))?;
    let resolution = fields
        .get("resolution")
        .and_then(|r| r.split_once('x'))
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
        .ok_or_else(|| missing("resolution"))?;
    let recorded = Recorded {
        mask: field(&fields, "mask").ok_or_else(|| missing("mask"))?,
        scene_file: fields.get("scene_file").map(|f| (PathBuf::from(f), defines)),
        algorithm: field(&fields, "algorithm").ok_or_else(|| missing("algorithm"))?,
        resolution,
        max_length: field(&fields, "max_length").ok_or_else(|| missing("max_length"))?,
        seed: field(&fields, "seed").ok_or_else(|| missing("seed"))?,
        radius_factor: field(&fields, "radius_factor").ok_or_else(|| missing("radius_factor"))?,
        radius_alpha: field(&fields, "radius_alpha").ok_or_else(|| missing("radius_alpha"))?,
        radius_mode: field(&fields, "radius_mode").ok_or_else(|| missing("radius_mode"))?,
        memory_efficient: field(&fields, "memory_efficient").ok_or_else(|| missing("memory_efficient"))?,
        spectral: match fields.get("spectral") {
            None => false,
            Some(_) => field(&fields, "spectral").ok_or_else(|| missing("spectral"))?,
        },
        russian_roulette: match fields.get("russian_roulette") {
            None => RussianRoulette::default(),
            Some(name) => RussianRoulette::from_name(name).ok_or_else(|| missing("russian_roulette"))?,
        },
        heuristic: match fields.get("heuristic") {
            None => Heuristic::default(),
            Some(name) => Heuristic::from_name(name).ok_or_else(|| missing("heuristic"))?,
        },
        film: fields.get("film").map_or_else(|| "fis".to_string(), |f| f.to_string()),
        fingerprint: Fingerprint { hash: scene_hash, files },
    };
    let iterations: u64 = field(&fields, "iterations").ok_or_else(|| missing("iterations"))?;
    let rejected: u64 = field(&fields, "rejected").ok_or_else(|| missing("rejected"))?;
    let data = &bytes[split + 2..];
    let (w, h) = recorded.resolution;
    let pixels = w as usize * h as usize;
    let expected = pixels * 48;
    if data.len() != expected {
        bail!(bad(format!("expected {expected} bytes of film for {w}x{h}, found {}", data.len())));
    }
    let mut triples = data.chunks_exact(24).map(|c| {
        let v = |i: usize| f64::from_le_bytes(c[i * 8..i * 8 + 8].try_into().expect("8 bytes"));
        [v(0), v(1), v(2)]
    });
    let sums = triples.by_ref().take(pixels).collect();
    let squares = triples.collect();
    let film = Film::from_sums(w, h, sums, squares, iterations, rejected).ok_or_else(|| bad("film size".into()))?;
    Ok((recorded, film))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact_and_bad_files_fail_clearly() {
        let dir = std::env::temp_dir().join(format!("vcm-checkpoint-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.ckpt");
        let mut recorded = Recorded {
            mask: 450,
            scene_file: None,
            algorithm: "vcm".into(),
            resolution: (3, 2),
            max_length: 7,
            seed: 99,
            radius_factor: 0.003,
            radius_alpha: 0.75,
            radius_mode: "per-pixel".into(),
            memory_efficient: true,
            spectral: true,
            russian_roulette: RussianRoulette::Albedo,
            heuristic: Heuristic::Power,
            film: "splat".into(),
            fingerprint: Fingerprint::builtin(450, (3, 2)),
        };
        let sums: Vec<[f64; 3]> = (0..6).map(|i| [i as f64 * 0.1, 1.0 / 3.0, f64::MIN_POSITIVE]).collect();
        let squares: Vec<[f64; 3]> = (0..6).map(|i| [i as f64, 0.5, 1e300]).collect();
        let film = Film::from_sums(3, 2, sums.clone(), squares.clone(), 17, 2).unwrap();
        save(&path, &recorded, &film).unwrap();
        let (back, film_back) = load(&path).unwrap();
        assert_eq!(back, recorded);
        assert_eq!(film_back.sums(), &sums[..]);
        // A scene file with its parameters.
        recorded.scene_file = Some((PathBuf::from("scenes/a b.xml"), vec!["spp=4".into(), "res=x=y".into()]));
        recorded.fingerprint = Fingerprint::from_parts(
            vec![(PathBuf::from("scenes/a b.xml"), 7), (PathBuf::from("m/x=1 .ply"), u64::MAX)],
            &["spp=4".into()],
        );
        save(&path, &recorded, &film).unwrap();
        assert_eq!(load(&path).unwrap().0, recorded);
        assert_eq!(film_back.sum_squares(), &squares[..]);
        assert_eq!((film_back.iterations(), film_back.rejected_samples()), (17, 2));
        assert!(!dir.join("a.ckpt.tmp").exists(), "the temporary file is renamed");
        // Truncated film.
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 5]).unwrap();
        let message = load(&path).unwrap_err().to_string();
        assert!(message.contains("expected 288 bytes"), "{message}");
        std::fs::write(&path, b"hello\n\n").unwrap();
        assert!(load(&path).unwrap_err().to_string().contains("first line"));
        // Another version, and the previous format.
        let text = String::from_utf8_lossy(&bytes[..bytes.len() - 5]).replace(VERSION, "0.0.1-other");
        std::fs::write(&path, text.as_bytes()).unwrap();
        let message = load(&path).unwrap_err().to_string();
        assert!(message.contains("written by vcm 0.0.1-other") && message.contains(VERSION), "{message}");
        std::fs::write(&path, b"vcm-checkpoint 2\nmask=1\n\n").unwrap();
        let message = load(&path).unwrap_err().to_string();
        assert!(message.contains("has format 2") && message.contains("reads format 3"), "{message}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
