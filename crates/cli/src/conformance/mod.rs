//! `vcm conformance DIR`: renders every scene of Mitsuba 3's render test suite (its
//! `tests/scenes` folder) with each requested algorithm through a render session (the code path
//! of `vcm render --variance`) and judges it against the suite's references by
//! [`verdict::judge`]. Prints a table on stdout, progress on stderr, and with `--markdown` writes
//! the table with its provenance. The suite's layout is in [`suite`]; the outputs in [`table`].

mod provenance;
mod suite;
mod table;
mod verdict;

use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result, bail, ensure};
use render::Algorithm;
use render::driver::Budget;
use session::{Notice, SceneSource};

use suite::Case;
use table::{Outcome, SceneStatus, Table};
use verdict::Criteria;

/// Mitsuba 3's render tests give each render this many samples in total (samples per pixel =
/// this / pixels).
pub const MITSUBA_SAMPLE_BUDGET: u64 = 2_000_000;

/// The fewest iterations of a default-budget render. Our variance of a pixel mean is estimated
/// from the spread of the iterations (n − 1 degrees of freedom, relative standard deviation
/// √(2/(n−1)) for Gaussian samples: 53 % at 8 iterations, 18 % at 64); with a handful of
/// iterations a pixel whose samples happen to agree gets variance 0 and fails the Z-test
/// however right its mean is (Mitsuba's `various_shapes` scene at its 8 spp: 2444 of the 4354
/// failing entries of a pt render had zero variance). Mitsuba's own test never estimates the
/// test render's variance; ours does, so it needs enough iterations.
pub const MIN_ITERATIONS: u64 = 64;

/// Iterations of a render of `pixels` pixels at Mitsuba's budget, at least [`MIN_ITERATIONS`].
pub fn default_iterations(pixels: u64) -> u64 {
    (MITSUBA_SAMPLE_BUDGET / pixels.max(1)).max(MIN_ITERATIONS)
}

/// The default budget factor of `--escalate`.
pub const DEFAULT_ESCALATION: u64 = 16;

/// The budget of the escalated render of a cell that failed at `budget`: `factor` times the
/// iterations or the time.
///
/// Why a failing cell gets a second, longer render. The Z-test assumes each pixel mean is nearly
/// normal with the variance estimated from the iterations. Where a contribution arrives as rare
/// large samples, that fails at a few dozen iterations: most pixels see none of the events, so
/// their mean sits below the truth and their estimated variance is too small to cover the gap,
/// and the failing entries are all on the low side (Mitsuba's `various_emitters` with `pt` at 64
/// spp: 97.27 % of the entries pass, every failing one below the reference, while the image
/// mean agrees within 0.11 %; at 1024 spp 99.94 % pass). A bias does not go away with a longer
/// render: the render's standard error falls by √factor while the bias stays, so a render
/// that fails the first test for a bias is more likely to fail the second. The retry adds to a
/// biased render's chance of passing at most the chance that the longer render passes, which
/// falls with the budget.
pub fn escalated_budget(budget: Budget, factor: u64) -> Budget {
    match budget {
        Budget::Iterations(n) => Budget::Iterations(n.saturating_mul(factor)),
        Budget::Time(t) => Budget::Time(t.saturating_mul(u32::try_from(factor).unwrap_or(u32::MAX))),
    }
}

/// The seed of an escalated render: another stream family than the first render's.
fn escalated_seed(seed: u64) -> u64 {
    seed ^ 0x9e37_79b9_7f4a_7c15
}

/// Arguments of `vcm conformance`.
#[derive(clap::Args, Debug, Clone)]
pub struct ConformanceArgs {
    /// The suite: Mitsuba 3's `tests/scenes` folder (from the mitsuba-data repository, with
    /// `tests/common` beside it).
    pub dir: PathBuf,
    /// Algorithms to render each scene with, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "pt,vcm")]
    pub algorithms: Vec<String>,
    /// Iterations (samples per pixel) per render [default: Mitsuba's budget, 2·10⁶ samples per
    /// image, at least 64 (the variance estimate needs them)].
    #[arg(long, value_name = "N", conflicts_with = "time")]
    pub spp: Option<u64>,
    /// Render each scene for this many seconds per algorithm instead.
    #[arg(long, value_name = "SECONDS")]
    pub time: Option<f64>,
    /// Samples per pixel of the references (their variance images hold the variance of one
    /// sample; Mitsuba 3's reference script renders 32000).
    #[arg(long, value_name = "N", default_value_t = 32000.0)]
    pub reference_spp: f64,
    /// Only scenes whose `group/name` contains this text.
    #[arg(long, value_name = "TEXT")]
    pub filter: Option<String>,
    /// Load scene files permissively (unsupported parameters become warnings; the render may
    /// then differ from the file).
    #[arg(long)]
    pub permissive: bool,
    /// Seed of the random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub threads: usize,
    /// Light sampler of the path tracer, as `vcm render --light-sampler`.
    #[arg(long, default_value = "tree", value_name = "tree|power", value_parser = crate::parse_light_sampler)]
    pub light_sampler: render::path_tracer::LightSampler,
    /// MIS compensation for image environments, as `vcm render --mis-compensation`.
    #[arg(long, default_value = "on", value_name = "on|off", value_parser = crate::parse_on_off, action = clap::ArgAction::Set)]
    pub mis_compensation: bool,
    /// Russian roulette of the path tracer, as `vcm render --rr-depth` (`file`: the scene
    /// file's integrator rr_depth, Mitsuba's default 5).
    #[arg(long, default_value = "albedo", value_name = "N|albedo|file", value_parser = crate::parse_russian_roulette)]
    pub rr_depth: crate::RouletteArg,
    /// Film mode, as `vcm render --film` [default: splat, the scene files' default].
    #[arg(long, value_name = "splat|fis", value_parser = crate::parse_film)]
    pub film: Option<scene::filter::FilmMode>,
    /// A cell that fails is rendered once more, with another seed, at this many times its
    /// budget, and judged by that render (the table shows both). 1 turns it off. See
    /// [`escalated_budget`].
    #[arg(long, value_name = "FACTOR", default_value_t = DEFAULT_ESCALATION)]
    pub escalate: u64,
    /// Also write the table with date, commit, machine and command to this Markdown file.
    #[arg(long, value_name = "FILE")]
    pub markdown: Option<PathBuf>,
}

/// Runs `vcm conformance`.
pub fn run(args: ConformanceArgs) -> Result<()> {
    let algorithms: Vec<(String, Algorithm)> = args
        .algorithms
        .iter()
        .map(|name| {
            let name = name.trim().to_string();
            let algorithm = Algorithm::from_name(&name).with_context(|| {
                let valid: Vec<&str> = Algorithm::ALL.iter().map(|(_, n)| *n).collect();
                format!("--algorithms: unknown algorithm '{name}' (expected some of {})", valid.join(", "))
            })?;
            Ok((name, algorithm))
        })
        .collect::<Result<_>>()?;
    ensure!(!algorithms.is_empty(), "--algorithms: name at least one algorithm");
    ensure!(args.escalate >= 1, "--escalate must be at least 1 (1: no escalated renders), got 0");
    if let Some(t) = args.time {
        ensure!(t.is_finite() && t > 0.0, "--time must be a positive number of seconds, got {t}");
    }
    if args.spp == Some(0) {
        bail!("--spp must be at least 1");
    }
    ensure!(
        args.reference_spp.is_finite() && args.reference_spp >= 1.0,
        "--reference-spp must be at least 1, got {}",
        args.reference_spp
    );
    let cases: Vec<Case> = suite::discover(&args.dir)?
        .into_iter()
        .filter(|c| args.filter.as_ref().is_none_or(|f| c.label().contains(f.as_str())))
        .collect();
    ensure!(!cases.is_empty(), "--filter: no scene of '{}' matches", args.dir.display());

    let criteria = Criteria::MITSUBA;
    let mut rows = Vec::new();
    for (index, case) in cases.iter().enumerate() {
        eprintln!("[{}/{}] {}", index + 1, cases.len(), case.label());
        let status = match judge_case(case, &algorithms, &args, &criteria) {
            // File names relative to the suite, to keep the lines short.
            SceneStatus::LoadError(error) => SceneStatus::LoadError(relative_to(&error, &args.dir)),
            status => status,
        };
        rows.push((case.label(), status));
    }
    let table = Table { algorithms: algorithms.iter().map(|(n, _)| n.clone()).collect(), rows };
    print!("{}", table.plain());
    if let Some(path) = &args.markdown {
        let provenance = provenance::collect(&budget_words(&args), args.reference_spp, args.escalate);
        std::fs::write(path, table.markdown(&provenance, &criteria))
            .with_context(|| format!("cannot write '{}'", path.display()))?;
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}

/// Loads, renders and judges one scene with every algorithm.
fn judge_case(
    case: &Case,
    algorithms: &[(String, Algorithm)],
    args: &ConformanceArgs,
    criteria: &Criteria,
) -> SceneStatus {
    let source = SceneSource::File(case.scene.clone(), Vec::new());
    let pixels = match catch(|| session::load_scene(&source, None, args.permissive)) {
        Ok(loaded) => u64::from(loaded.scene.camera.width) * u64::from(loaded.scene.camera.height),
        Err(error) => {
            eprintln!("  does not load: {error}");
            return SceneStatus::LoadError(error);
        }
    };
    if !case.has_references() {
        return SceneStatus::NoReference;
    }
    let budget = match (args.spp, args.time) {
        (Some(n), _) => Budget::Iterations(n),
        (None, Some(t)) => Budget::Time(Duration::from_secs_f64(t)),
        (None, None) => Budget::Iterations(default_iterations(pixels)),
    };
    let reference = match read_reference(case, args.reference_spp) {
        Ok(images) => images,
        Err(error) => return SceneStatus::LoadError(format!("reference: {}", first_line(&format!("{error:#}")))),
    };
    let outcomes = algorithms
        .iter()
        .map(|(name, algorithm)| {
            let outcome = render_and_judge(case, *algorithm, budget, args.seed, args, &reference, criteria);
            report(name, &outcome);
            match outcome {
                Outcome::Judged { iterations, verdict, .. } if !verdict.passed && args.escalate > 1 => {
                    eprintln!("  {name}: rendering again at {}× the budget", args.escalate);
                    let longer = escalated_budget(budget, args.escalate);
                    let seed = escalated_seed(args.seed);
                    let second = render_and_judge(case, *algorithm, longer, seed, args, &reference, criteria);
                    report(name, &second);
                    match second {
                        Outcome::Judged { iterations: n, verdict: v, .. } => Outcome::Judged {
                            iterations: n,
                            verdict: v,
                            first: Some(Box::new(table::FirstTry { iterations, verdict })),
                        },
                        failed => failed,
                    }
                }
                outcome => outcome,
            }
        })
        .collect();
    SceneStatus::Rendered(outcomes)
}

/// Prints one render's verdict under the scene's progress line.
fn report(name: &str, outcome: &Outcome) {
    match outcome {
        Outcome::Judged { iterations, verdict, .. } => eprintln!(
            "  {name}: {} ({iterations} spp, {:.2} % of entries pass, worst mean ratio {:.4})",
            if verdict.passed { "PASS" } else { "FAIL" },
            100.0 * verdict.pass_fraction(),
            verdict.worst_mean_ratio()
        ),
        Outcome::Failed(error) => eprintln!("  {name}: error: {error}"),
    }
}

/// Mitsuba's own render test floors the reference's per-sample variance at this value before
/// its Z-test (`reference_var = np.maximum(reference_var, 1e-4)` in mitsuba3's
/// `src/render/tests/test_renders.py`): its variance images hold tiny negative values where the
/// image is exactly 0, which would otherwise make z = ±1000 for a render that is exactly right.
pub(crate) const REFERENCE_VARIANCE_FLOOR: f64 = 1e-4;

/// The reference image and the variance of its pixel means (the file's per-sample variance,
/// floored at [`REFERENCE_VARIANCE_FLOOR`] as Mitsuba's test does, divided by `reference_spp`).
fn read_reference(case: &Case, reference_spp: f64) -> Result<(io::Image, io::Image)> {
    let image = io::read_image(&case.reference)?;
    let mut variance = io::read_image(&case.reference_variance)?;
    for pixel in &mut variance.pixels {
        // NaN stays NaN: the verdict leaves such entries out and counts them.
        *pixel = pixel.map(|v| {
            let v = f64::from(v);
            (if v.is_nan() { v } else { v.max(REFERENCE_VARIANCE_FLOOR) } / reference_spp) as f32
        });
    }
    Ok((image, variance))
}

/// Renders `case` with `algorithm` through a session and judges the result.
fn render_and_judge(
    case: &Case,
    algorithm: Algorithm,
    budget: Budget,
    seed: u64,
    args: &ConformanceArgs,
    (reference, reference_variance): &(io::Image, io::Image),
    criteria: &Criteria,
) -> Outcome {
    let mut request = session::Request::new(SceneSource::File(case.scene.clone(), Vec::new()));
    request.algorithm = algorithm;
    request.budget = Some(budget);
    request.seed = seed;
    request.threads = args.threads;
    request.permissive = args.permissive;
    request.keep_variance = true;
    request.film = args.film;
    request.light_sampler = args.light_sampler;
    request.mis_compensation = args.mis_compensation;
    request.russian_roulette = args.rr_depth.0;
    // The verdict takes the render's error from the spread of its iterations, which needs them
    // independent (the stratified sequence's are not, render::primary_samples).
    request.sampler = render::primary_samples::PrimarySamples::Independent;
    let rendered = catch(|| session::render(&request, None, &mut Quiet));
    let film = match rendered {
        Ok(outcome) => outcome.output.film,
        Err(error) => return Outcome::Failed(error),
    };
    let (width, height) = (film.width() as usize, film.height() as usize);
    let image = io::Image { width, height, pixels: film.mean() };
    let Some(pixels) = film.variance_of_mean() else {
        return Outcome::Failed("the film kept no variance".to_string());
    };
    let variance = io::Image { width, height, pixels };
    match verdict::judge(&image, &variance, reference, reference_variance, criteria) {
        Ok(verdict) => Outcome::Judged { iterations: film.iterations(), verdict, first: None },
        Err(error) => Outcome::Failed(first_line(&format!("{error:#}"))),
    }
}

/// Runs `work`, turning its error or panic into the first line of a message.
fn catch<T>(work: impl FnOnce() -> Result<T>) -> std::result::Result<T, String> {
    match std::panic::catch_unwind(AssertUnwindSafe(work)) {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(error)) => Err(first_line(&format!("{error:#}"))),
        Err(payload) => {
            let message = payload
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".to_string());
            Err(format!("panicked: {}", first_line(&message)))
        }
    }
}

/// `text` with every occurrence of `dir/` removed.
fn relative_to(text: &str, dir: &std::path::Path) -> String {
    let prefix = format!("{}/", dir.display().to_string().trim_end_matches('/'));
    text.replace(&prefix, "")
}

fn first_line(text: &str) -> String {
    text.lines().next().unwrap_or("").trim().to_string()
}

/// The per-render budget in words, for the Markdown document.
fn budget_words(args: &ConformanceArgs) -> String {
    let first = match (args.spp, args.time) {
        (Some(n), _) => format!("{n} samples per pixel per render"),
        (None, Some(t)) => format!("{t} s of wall-clock time per render"),
        (None, None) => {
            format!(
                "Mitsuba's budget: {MITSUBA_SAMPLE_BUDGET} samples per image (samples per pixel = that / pixels), at \
                 least {MIN_ITERATIONS} samples per pixel (our variance is estimated from the iterations)"
            )
        }
    };
    match args.escalate {
        1 => first,
        factor => format!("{first}; a failing cell is rendered again at {factor}× that (see Rule)"),
    }
}

/// Passes the session's warnings and notes to stderr, indented under the scene's progress
/// line; drops its progress messages.
struct Quiet;

impl session::Observer for Quiet {
    fn notice(&mut self, notice: Notice) {
        if !matches!(notice, Notice::Progress(_)) {
            eprintln!("  {notice}");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_escalated_render_multiplies_the_budget_and_changes_the_seed() {
        assert!(matches!(escalated_budget(Budget::Iterations(64), 16), Budget::Iterations(1024)));
        assert!(matches!(escalated_budget(Budget::Iterations(u64::MAX), 16), Budget::Iterations(u64::MAX)));
        assert!(
            matches!(escalated_budget(Budget::Time(Duration::from_secs(2)), 16), Budget::Time(t) if t == Duration::from_secs(32))
        );
        assert_ne!(escalated_seed(0), 0);
        assert_ne!(escalated_seed(7), 7);
    }

    #[test]
    fn the_default_budget_is_mitsubas_with_a_floor_for_the_variance_estimate() {
        assert_eq!(default_iterations(256 * 256), 64, "Mitsuba's 30 spp is raised to 64");
        assert_eq!(default_iterations(48 * 48), 868);
        assert_eq!(default_iterations(512 * 64), 64, "61 spp is raised to 64");
        assert_eq!(default_iterations(0), MITSUBA_SAMPLE_BUDGET);
    }
}
