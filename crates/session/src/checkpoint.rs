//! Checkpoint files: everything needed to continue a progressive render exactly where it
//! stopped — the render's settings, the film's per-pixel sums (f64) and its iteration and
//! rejected-sample counts. The random streams are keyed by (seed, iteration, path), and the
//! radius schedule by the iteration index, so a resumed render equals an uninterrupted one.
//!
//! Format (version 4): the line `vcm-checkpoint 4`, then `key=value` lines, an empty line, the
//! sums and then the sums of squares, row-major: little-endian f64 triples for a film with f64
//! sums (`sums=float`), little-endian i128 triples (units of 2⁻⁶⁴ and 2⁻⁴⁰, see
//! [`scene::Summation::Fixed`]) for fixed-point sums (`sums=fixed`). Files are written to
//! `FILE.tmp` and renamed over `FILE`, so a crash never leaves a truncated checkpoint.
//!
//! Version 3 added what the checkpoint rendered: `vcm_version` (the crate version of the
//! binary that wrote it; a different version may render differently, so it must match),
//! `scene_hash` and one `scene_read=HASH PATH` line per file the scene loader read
//! ([`Fingerprint`]). Version 2 files (no scene record) are refused with a message: resume
//! them with the binary that wrote them. Version 4 added `sums`, `first_iteration`, `largest`
//! (fixed-point films) and, for a slice of a render ([`crate::slice`]), `slice=K/N` and
//! `slice_iterations`; version 3 files are read as f64 films from iteration 0.

use render::path_tracer::{Heuristic, LightSampler, RussianRoulette};
use render::primary_samples::PrimarySamples;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use scene::{Film, FilmSums, Summation};

use crate::fingerprint::Fingerprint;
use crate::slice::{Slice, SliceSpec};

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
    /// Volume radius factor (absent in checkpoints written before it existed: the default,
    /// [`render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR`]; only renders of scenes with media use it).
    pub volume_radius_factor: f32,
    /// `global`, `fixed` or `per-pixel`.
    pub radius_mode: String,
    /// Memory-efficient mode.
    pub memory_efficient: bool,
    /// Spectral mode (absent in checkpoints written before it existed: RGB).
    pub spectral: bool,
    /// Russian roulette of the path tracer, as resolved for the render
    /// ([`crate::resolve_russian_roulette`]; absent in checkpoints written before it existed:
    /// the albedo rule, then the only one).
    pub russian_roulette: RussianRoulette,
    /// MIS heuristic of the path tracer.
    pub heuristic: Heuristic,
    /// Light sampler of the path tracer (absent in checkpoints written before it existed:
    /// `power`, the only one then).
    pub light_sampler: LightSampler,
    /// MIS compensation for image environments (absent in checkpoints written before it was
    /// recorded: on, the default since; both settings estimate the same image).
    pub mis_compensation: bool,
    /// Where the path tracer's first vertices' numbers come from (absent in checkpoints written
    /// before it existed: `independent`, the only one then).
    pub sampler: PrimarySamples,
    /// Film mode, `fis` or `splat` (absent in checkpoints written before it existed: `fis`).
    pub film: String,
    /// What the scene was built from.
    pub fingerprint: Fingerprint,
    /// How the film adds iterations (absent in version 3: f64).
    pub sums: Summation,
    /// The slice of the render this checkpoint holds (`None`: the whole render).
    pub slice: Option<Slice>,
}

/// The checkpoint format this binary reads and writes.
pub const FORMAT: u32 = 4;
const MAGIC: &str = "vcm-checkpoint 4";
/// The previous format, still read (f64 films from iteration 0).
const MAGIC_3: &str = "vcm-checkpoint 3";
/// The renderer version recorded in (and required of) checkpoints.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Writes `film` and `recorded` to `path` atomically (write, then rename).
pub fn save(path: &Path, recorded: &Recorded, film: &Film) -> Result<()> {
    if !film.has_variance() {
        bail!("internal error: a checkpoint needs a film that keeps its sums of squares");
    }
    if film.summation() != recorded.sums {
        bail!(
            "internal error: the film's sums are {}, the checkpoint records {}",
            film.summation().name(),
            recorded.sums.name()
        );
    }
    let temporary = PathBuf::from(format!("{}.tmp", path.display()));
    let write = || -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(std::fs::File::create(&temporary)?);
        writeln!(out, "{MAGIC}")?;
        for line in header_lines(recorded) {
            writeln!(out, "{line}")?;
        }
        writeln!(out, "iterations={}", film.iterations())?;
        writeln!(out, "first_iteration={}", film.first_iteration())?;
        writeln!(out, "rejected={}", film.rejected_samples())?;
        if let FilmSums::Fixed { largest, .. } = film.raw_sums() {
            writeln!(out, "largest={largest}")?;
        }
        writeln!(out)?;
        match film.raw_sums() {
            FilmSums::Float { sums, squares } => {
                for value in sums.iter().chain(squares).flatten() {
                    out.write_all(&value.to_le_bytes())?;
                }
            }
            FilmSums::Fixed { sums, squares, .. } => {
                for value in sums.iter().chain(squares).flatten() {
                    out.write_all(&value.to_le_bytes())?;
                }
            }
        }
        out.into_inner().map_err(|e| e.into_error())?.sync_all()
    };
    write().with_context(|| format!("cannot write checkpoint '{}'", temporary.display()))?;
    std::fs::rename(&temporary, path)
        .with_context(|| format!("cannot move checkpoint '{}' to '{}'", temporary.display(), path.display()))
}

/// The settings lines of a checkpoint header (`key=value`, in file order, without the film's
/// counts): what must be equal for two checkpoints to be parts of one render.
pub fn header_lines(r: &Recorded) -> Vec<String> {
    let mut lines = vec![format!("vcm_version={VERSION}"), format!("scene_hash={:016x}", r.fingerprint.hash)];
    for (file, hash) in &r.fingerprint.files {
        lines.push(format!("scene_read={hash:016x} {}", file.display()));
    }
    lines.push(format!("mask={}", r.mask));
    if let Some((file, defines)) = &r.scene_file {
        lines.push(format!("scene_file={}", file.display()));
        for define in defines {
            lines.push(format!("define={define}"));
        }
    }
    lines.push(format!("algorithm={}", r.algorithm));
    lines.push(format!("resolution={}x{}", r.resolution.0, r.resolution.1));
    lines.push(format!("max_length={}", r.max_length));
    lines.push(format!("seed={}", r.seed));
    lines.push(format!("radius_factor={}", r.radius_factor));
    lines.push(format!("radius_alpha={}", r.radius_alpha));
    lines.push(format!("volume_radius_factor={}", r.volume_radius_factor));
    lines.push(format!("radius_mode={}", r.radius_mode));
    lines.push(format!("memory_efficient={}", r.memory_efficient));
    lines.push(format!("spectral={}", r.spectral));
    lines.push(format!("russian_roulette={}", r.russian_roulette.name()));
    lines.push(format!("heuristic={}", r.heuristic.name()));
    lines.push(format!("light_sampler={}", r.light_sampler.name()));
    lines.push(format!("mis_compensation={}", r.mis_compensation));
    lines.push(format!("sampler={}", r.sampler.name()));
    lines.push(format!("film={}", r.film));
    lines.push(format!("sums={}", r.sums.name()));
    if let Some(slice) = &r.slice {
        lines.push(format!("slice={}", slice.name()));
        lines.push(format!("slice_iterations={}", slice.iterations));
    }
    lines
}

/// Reads a checkpoint: its settings and its film.
pub fn load(path: &Path) -> Result<(Recorded, Film)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read checkpoint '{}'", path.display()))?;
    let bad = |what: String| anyhow::anyhow!("'{}' is not a valid vcm checkpoint: {what}", path.display());
    let split = bytes.windows(2).position(|w| w == b"\n\n").ok_or_else(|| bad("no end of header".into()))?;
    let header = std::str::from_utf8(&bytes[..split]).map_err(|_| bad("the header is not text".into()))?;
    let mut lines = header.lines();
    match lines.next() {
        Some(MAGIC | MAGIC_3) => {}
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
        volume_radius_factor: match fields.get("volume_radius_factor") {
            None => render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR,
            Some(_) => field(&fields, "volume_radius_factor").ok_or_else(|| missing("volume_radius_factor"))?,
        },
        radius_mode: field(&fields, "radius_mode").ok_or_else(|| missing("radius_mode"))?,
        memory_efficient: field(&fields, "memory_efficient").ok_or_else(|| missing("memory_efficient"))?,
        spectral: match fields.get("spectral") {
            None => false,
            Some(_) => field(&fields, "spectral").ok_or_else(|| missing("spectral"))?,
        },
        russian_roulette: match fields.get("russian_roulette") {
            // Checkpoints from before the policy was recorded were rendered with the albedo rule.
            None => RussianRoulette::Albedo,
            Some(name) => RussianRoulette::from_name(name).ok_or_else(|| missing("russian_roulette"))?,
        },
        heuristic: match fields.get("heuristic") {
            None => Heuristic::default(),
            Some(name) => Heuristic::from_name(name).ok_or_else(|| missing("heuristic"))?,
        },
        sampler: match fields.get("sampler") {
            None => PrimarySamples::Independent,
            Some(name) => PrimarySamples::from_name(name).ok_or_else(|| missing("sampler"))?,
        },
        light_sampler: match fields.get("light_sampler") {
            None => LightSampler::Power,
            Some(name) => LightSampler::from_name(name).ok_or_else(|| missing("light_sampler"))?,
        },
        mis_compensation: match fields.get("mis_compensation") {
            None => true,
            Some(_) => field(&fields, "mis_compensation").ok_or_else(|| missing("mis_compensation"))?,
        },
        film: fields.get("film").map_or_else(|| "fis".to_string(), |f| f.to_string()),
        fingerprint: Fingerprint { hash: scene_hash, files },
        sums: match fields.get("sums") {
            None => Summation::Float,
            Some(name) => Summation::from_name(name).ok_or_else(|| missing("sums"))?,
        },
        slice: match fields.get("slice") {
            None => None,
            Some(text) => {
                let spec = SliceSpec::parse(text).map_err(|_| missing("slice"))?;
                let iterations = field(&fields, "slice_iterations").ok_or_else(|| missing("slice_iterations"))?;
                Some(Slice { index: spec.index, count: spec.count, iterations })
            }
        },
    };
    let iterations: u64 = field(&fields, "iterations").ok_or_else(|| missing("iterations"))?;
    let rejected: u64 = field(&fields, "rejected").ok_or_else(|| missing("rejected"))?;
    let first_iteration: u64 = match fields.get("first_iteration") {
        None => 0,
        Some(_) => field(&fields, "first_iteration").ok_or_else(|| missing("first_iteration"))?,
    };
    let data = &bytes[split + 2..];
    let (w, h) = recorded.resolution;
    let pixels = w as usize * h as usize;
    let value_bytes = match recorded.sums {
        Summation::Float => 8,
        Summation::Fixed => 16,
    };
    let expected = pixels * 6 * value_bytes;
    if data.len() != expected {
        bail!(bad(format!("expected {expected} bytes of film for {w}x{h}, found {}", data.len())));
    }
    let sums = match recorded.sums {
        Summation::Float => {
            let mut triples = data
                .chunks_exact(24)
                .map(|c| std::array::from_fn(|i| f64::from_le_bytes(c[i * 8..i * 8 + 8].try_into().expect("8 bytes"))));
            let sums = triples.by_ref().take(pixels).collect();
            FilmSums::Float { sums, squares: triples.collect() }
        }
        Summation::Fixed => {
            let mut triples = data.chunks_exact(48).map(|c| {
                std::array::from_fn(|i| i128::from_le_bytes(c[i * 16..i * 16 + 16].try_into().expect("16 bytes")))
            });
            let sums = triples.by_ref().take(pixels).collect();
            let largest = field(&fields, "largest").ok_or_else(|| missing("largest"))?;
            FilmSums::Fixed { sums, squares: triples.collect(), largest }
        }
    };
    let film =
        Film::from_raw(w, h, sums, first_iteration, iterations, rejected).ok_or_else(|| bad("film size".into()))?;
    Ok((recorded, film))
}

#[cfg(test)]
mod tests {
    use super::*;
    use testkit::TempDir;

    #[test]
    fn round_trip_is_exact_and_bad_files_fail_clearly() {
        let dir = TempDir::new("checkpoint-test");
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
            volume_radius_factor: 0.025,
            radius_mode: "per-pixel".into(),
            memory_efficient: true,
            spectral: true,
            russian_roulette: RussianRoulette::Albedo,
            heuristic: Heuristic::Power,
            light_sampler: LightSampler::Power,
            mis_compensation: true,
            sampler: PrimarySamples::Independent,
            film: "splat".into(),
            fingerprint: Fingerprint::builtin(450, (3, 2)),
            sums: Summation::Float,
            slice: None,
        };
        let sums: Vec<[f64; 3]> = (0..6).map(|i| [i as f64 * 0.1, 1.0 / 3.0, f64::MIN_POSITIVE]).collect();
        let squares: Vec<[f64; 3]> = (0..6).map(|i| [i as f64, 0.5, 1e300]).collect();
        let raw = FilmSums::Float { sums: sums.clone(), squares: squares.clone() };
        let film = Film::from_raw(3, 2, raw, 0, 17, 2).unwrap();
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
        assert!(message.contains("has format 2") && message.contains("reads format 4"), "{message}");
        // Format 3 (no sums, first iteration, slice or light-sampler lines) is read as an f64
        // film from 0 rendered with the power light selection.
        recorded.scene_file = None;
        recorded.fingerprint = Fingerprint::builtin(450, (3, 2));
        save(&path, &recorded, &film).unwrap();
        let text = std::fs::read(&path).unwrap();
        let header_end = text.windows(2).position(|w| w == b"\n\n").unwrap();
        let header = String::from_utf8_lossy(&text[..header_end])
            .replace("vcm-checkpoint 4", "vcm-checkpoint 3")
            .replace("\nsums=float", "")
            .replace("\nfirst_iteration=0", "")
            // Written before the light sampler existed: power selection.
            .replace("\nlight_sampler=power", "")
            // Written before the MIS compensation was recorded: on.
            .replace("\nmis_compensation=true", "");
        std::fs::write(&path, [header.as_bytes(), &text[header_end..]].concat()).unwrap();
        let (back, film_back) = load(&path).unwrap();
        assert_eq!((back, film_back.sums().to_vec(), film_back.first_iteration()), (recorded, sums, 0));
    }

    #[test]
    fn fixed_point_slices_round_trip_exactly() {
        let dir = TempDir::new("checkpoint-fixed");
        let path = dir.join("part-1.ckpt");
        let slice = Slice { index: 1, count: 3, iterations: 10 };
        let recorded = Recorded {
            mask: 1,
            scene_file: None,
            algorithm: "pt".into(),
            resolution: (2, 1),
            max_length: 5,
            seed: 3,
            radius_factor: 0.003,
            radius_alpha: 0.75,
            volume_radius_factor: 0.025,
            radius_mode: "global".into(),
            memory_efficient: false,
            spectral: false,
            russian_roulette: RussianRoulette::Albedo,
            heuristic: Heuristic::Balance,
            light_sampler: LightSampler::Tree,
            mis_compensation: false,
            sampler: PrimarySamples::Sobol,
            film: "fis".into(),
            fingerprint: Fingerprint::builtin(1, (2, 1)),
            sums: Summation::Fixed,
            slice: Some(slice),
        };
        let mut film = Film::with_summation(2, 1, true, Summation::Fixed).starting_at(slice.range().start);
        let pixels = vec![spectrum::Rgb::new(1e-9, 0.3, 7e8), spectrum::Rgb::new(-2.5, 1.0 / 3.0, 0.0)];
        for _ in slice.range() {
            film.add_iteration(&scene::FrameBuffer { width: 2, height: 1, pixels: pixels.clone() }, 1);
        }
        save(&path, &recorded, &film).unwrap();
        let (back, film_back) = load(&path).unwrap();
        assert_eq!(back, recorded);
        assert_eq!(film_back.raw_sums(), film.raw_sums());
        assert_eq!((film_back.first_iteration(), film_back.iterations(), film_back.rejected_samples()), (3, 3, 3));
        // A film in the other mode than the record is refused.
        let float = Film::new(2, 1);
        assert!(save(&path, &recorded, &float).unwrap_err().to_string().contains("internal error"));
    }
}
