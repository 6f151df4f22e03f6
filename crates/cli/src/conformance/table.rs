//! The outputs of `vcm conformance`: the plain-text table for stdout and the Markdown document
//! (the same table with the run's provenance, the rule and how to fetch the suite).

use std::fmt::Write as _;

use super::verdict::{Criteria, Verdict};

/// What happened to one scene.
#[derive(Clone, Debug)]
pub enum SceneStatus {
    /// The scene loads but a reference file is missing; not rendered.
    NoReference,
    /// The scene did not load: the loader's first error, on one line.
    LoadError(String),
    /// The scene loaded; one outcome per algorithm, in the order of [`Table::algorithms`].
    Rendered(Vec<Outcome>),
}

/// The result of one algorithm on one scene.
#[derive(Clone, Debug)]
pub enum Outcome {
    /// Rendered with this many iterations (samples per pixel) and judged. `first` is set when
    /// this is the escalated render of a cell whose render at the scene's budget failed: that
    /// first render's iterations and verdict.
    Judged { iterations: u64, verdict: Verdict, first: Option<Box<FirstTry>> },
    /// Rendering or comparing failed (or panicked): the first line of the error.
    Failed(String),
}

/// The failed render at the scene's budget that an escalated render replaced.
#[derive(Clone, Debug)]
pub struct FirstTry {
    /// Its iterations (samples per pixel).
    pub iterations: u64,
    /// Its verdict (a FAIL).
    pub verdict: Verdict,
}

/// The whole run.
#[derive(Clone, Debug)]
pub struct Table {
    /// Algorithm names (command-line spelling), one column each.
    pub algorithms: Vec<String>,
    /// `(scene label, status)` per scene, in suite order.
    pub rows: Vec<(String, SceneStatus)>,
}

impl Table {
    /// Counts `(scenes, loaded, passed per algorithm, of those passed by an escalated render)`.
    pub fn counts(&self) -> (usize, usize, Vec<usize>, Vec<usize>) {
        let mut loaded = 0;
        let mut passed = vec![0; self.algorithms.len()];
        let mut escalated = vec![0; self.algorithms.len()];
        for (_, status) in &self.rows {
            if let SceneStatus::Rendered(outcomes) = status {
                loaded += 1;
                for ((count, late), outcome) in passed.iter_mut().zip(escalated.iter_mut()).zip(outcomes) {
                    if let Outcome::Judged { verdict, first, .. } = outcome
                        && verdict.passed
                    {
                        *count += 1;
                        *late += usize::from(first.is_some());
                    }
                }
            }
        }
        (self.rows.len(), loaded, passed, escalated)
    }

    /// Rows as cells: scene, loads, one per algorithm.
    fn cells(&self) -> Vec<Vec<String>> {
        self.rows
            .iter()
            .map(|(label, status)| {
                let mut row = vec![label.clone()];
                match status {
                    SceneStatus::NoReference => row.push("no reference".into()),
                    SceneStatus::LoadError(_) => row.push("no".into()),
                    SceneStatus::Rendered(outcomes) => {
                        row.push("yes".into());
                        row.extend(outcomes.iter().map(cell));
                    }
                }
                row.resize(2 + self.algorithms.len(), "-".into());
                row
            })
            .collect()
    }

    fn header(&self) -> Vec<String> {
        let mut header = vec!["scene".to_string(), "loads".to_string()];
        header.extend(self.algorithms.iter().cloned());
        header
    }

    fn load_errors(&self) -> impl Iterator<Item = (&String, &String)> {
        self.rows.iter().filter_map(|(label, status)| match status {
            SceneStatus::LoadError(error) => Some((label, error)),
            _ => None,
        })
    }

    fn summary_line(&self) -> String {
        let (scenes, loaded, passed, escalated) = self.counts();
        let passes: Vec<String> = self
            .algorithms
            .iter()
            .zip(passed.iter().zip(&escalated))
            .map(|(a, (p, e))| if *e == 0 { format!("{a} {p}") } else { format!("{a} {p} ({e} of them escalated)") })
            .collect();
        format!("{scenes} scenes, {loaded} load and render; passed: {}", passes.join(", "))
    }

    /// The plain-text table with aligned columns, the load errors below it and a summary line.
    pub fn plain(&self) -> String {
        let header = self.header();
        let cells = self.cells();
        let widths: Vec<usize> = (0..header.len())
            .map(|i| cells.iter().map(|r| r[i].chars().count()).chain([header[i].len()]).max().unwrap_or(0))
            .collect();
        let line = |row: &[String]| {
            let padded: Vec<String> = row.iter().zip(&widths).map(|(c, w)| format!("{c:<w$}")).collect();
            padded.join("  ").trim_end().to_string()
        };
        let mut text = String::new();
        let _ = writeln!(text, "{}", line(&header));
        for row in &cells {
            let _ = writeln!(text, "{}", line(row));
        }
        let errors: Vec<_> = self.load_errors().collect();
        if !errors.is_empty() {
            let _ = writeln!(text, "\nload errors:");
            for (label, error) in errors {
                let _ = writeln!(text, "  {label}: {error}");
            }
        }
        let _ = writeln!(text, "\n{}", self.summary_line());
        text
    }

    /// The Markdown document: provenance, the rule, the table, the load errors, how to fetch
    /// the suite.
    pub fn markdown(&self, provenance: &Provenance, criteria: &Criteria) -> String {
        let mut md = String::new();
        let _ = writeln!(md, "# Conformance with Mitsuba 3's render test suite\n");
        let _ = writeln!(md, "Generated by `vcm conformance`; do not edit by hand (rerun the command below).\n");
        let _ = writeln!(md, "- date: {}", provenance.date);
        let _ = writeln!(md, "- commit: {}", provenance.commit);
        let _ = writeln!(md, "- machine: {}", provenance.machine);
        let _ = writeln!(md, "- command: `{}`", provenance.command);
        let _ = writeln!(md, "- budget: {}", provenance.budget);
        let _ = writeln!(md, "- result: {}\n", self.summary_line());
        let _ = writeln!(md, "## Rule\n");
        let _ = writeln!(
            md,
            "Each scene is rendered at its file's resolution with every algorithm, with the variance of \
             each pixel mean estimated from the spread of the iterations (as `vcm render --variance`). \
             For every pixel channel, z = (a − b) / sqrt(var_a + var_b), where var_b is the reference's \
             per-sample variance, floored at 1e-4 as Mitsuba's own render test does, divided by the \
             reference's sample count ({}); entries whose variances \
             are both zero get `vcm compare`'s floor of {} of the value. An entry passes when its \
             two-sided p-value is at least the Šidák level 1 − (1 − α)^(1/n) with α = {} over the n \
             pixel channels. A cell reads PASS iff at least {} % of the entries pass **and** every \
             channel's image mean is within {} % of the reference's or, where the means are noisier than \
             that, within their noise (two-sided p-value of the difference over its standard error \
             σ, from the same variances, at least the Šidák level of α = {} over the 3 channels); \
             it shows the fraction of passing entries, the channel mean ratio (render / reference) \
             farthest from 1, the largest relative σ of a channel mean's difference, and the \
             samples per pixel.\n",
            provenance.reference_spp,
            criteria.relative_floor,
            criteria.alpha,
            100.0 * criteria.pass_fraction,
            100.0 * criteria.mean_tolerance,
            criteria.mean_alpha
        );
        if provenance.escalation > 1 {
            let _ = writeln!(
                md,
                "A cell that fails is rendered once more, with another seed, at {0}× the budget, and \
                 the cell shows that render's verdict with the first one's after it. This is not a \
                 second chance for a wrong image: a bias that fails the first test is more likely to \
                 fail the second, because the render's standard error falls by √{0} while the bias \
                 stays; the retry adds to a biased render's chance of passing at most the chance \
                 that the {0}× render passes, which falls with the budget. What it forgives is a \
                 variance estimate that is too small at the first budget: where a contribution \
                 arrives as rare large samples (light reaching a wall only through a bounce off a \
                 small bright spot), most pixels see none of them in a few dozen iterations, so \
                 their mean sits below the truth with an estimated variance too small to cover it \
                 (the Z-test assumes the pixel mean is nearly normal, which such pixels are not \
                 yet). `--escalate 1` turns this off.\n",
                provenance.escalation
            );
        }
        let _ = writeln!(md, "## Results\n");
        let header = self.header();
        let _ = writeln!(md, "| {} |", header.join(" | "));
        let _ = writeln!(md, "|{}", "---|".repeat(header.len()));
        for row in self.cells() {
            let escaped: Vec<String> = row.iter().map(|c| c.replace('|', "\\|")).collect();
            let _ = writeln!(md, "| {} |", escaped.join(" | "));
        }
        let errors: Vec<_> = self.load_errors().collect();
        if !errors.is_empty() {
            let _ = writeln!(md, "\n### Load errors (the first error of each scene)\n");
            for (label, error) in errors {
                let _ = writeln!(md, "- `{label}`: {}", error.replace('`', "'"));
            }
        }
        let _ = writeln!(md, "\n## Getting the suite\n");
        let _ = writeln!(
            md,
            "The scenes and references are in the repository `mitsuba-renderer/mitsuba-data`, folder \
             `tests/scenes` (never commit them here). The scenes refer to `../../common` (shared meshes \
             and textures), so keep the repository's layout:\n\n\
             ```sh\n\
             git clone --depth 1 https://github.com/mitsuba-renderer/mitsuba-data\n\
             vcm conformance mitsuba-data/tests/scenes --markdown docs/conformance.md\n\
             ```\n\n\
             (`mitsuba-data/tests/common` must sit beside `mitsuba-data/tests/scenes`.) Grid \
             (heterogeneous) media are rendered by `pt` and by the VCM engine's algorithms \
             (`docs/media.md`)."
        );
        md
    }
}

/// Where and how a run was made, for the Markdown document.
#[derive(Clone, Debug)]
pub struct Provenance {
    /// UTC date and time.
    pub date: String,
    /// The source's commit.
    pub commit: String,
    /// CPU, cores, memory.
    pub machine: String,
    /// The command line.
    pub command: String,
    /// The per-render budget, in words.
    pub budget: String,
    /// Samples per pixel assumed for the references.
    pub reference_spp: f64,
    /// The budget factor of the escalated render of a failing cell (1: none).
    pub escalation: u64,
}

/// One algorithm's cell: `PASS 99.96% ×1.0021 ±0.08% (868 spp)`, and for an escalated render
/// `PASS 99.94% ×1.0005 ±0.02% (1024 spp; at 64 spp: FAIL 97.27% ×1.0011 ±0.09%)`.
fn cell(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Judged { iterations, verdict, first } => {
            let mut text = format!("{} ({iterations} spp", verdict_words(verdict));
            if let Some(first) = first {
                let _ = write!(text, "; at {} spp: {}", first.iterations, verdict_words(&first.verdict));
            }
            text + ")"
        }
        Outcome::Failed(error) => format!("error: {error}"),
    }
}

/// `PASS 99.96% ×1.0021 ±0.08%`: the verdict, the passing fraction, the worst mean ratio and the
/// largest relative standard error of a channel mean's difference.
fn verdict_words(verdict: &Verdict) -> String {
    format!(
        "{} {:.2}% ×{:.4} ±{:.2}%",
        if verdict.passed { "PASS" } else { "FAIL" },
        100.0 * verdict.pass_fraction(),
        verdict.worst_mean_ratio(),
        100.0 * verdict.largest_mean_error()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn verdict(passed: bool, passing: usize) -> Verdict {
        Verdict {
            entries: 1000,
            passing,
            excluded: 0,
            threshold_p: 1e-5,
            means_test: [1.0, 2.0, 3.03],
            means_reference: [1.0, 2.0, 3.0],
            mean_errors: [0.0, 0.0, 0.006],
            passed,
        }
    }

    #[test]
    fn table_lists_every_status() {
        let table = Table {
            algorithms: vec!["pt".into(), "vcm".into()],
            rows: vec![
                (
                    "g/a".into(),
                    SceneStatus::Rendered(vec![
                        Outcome::Judged { iterations: 64, verdict: verdict(true, 999), first: None },
                        Outcome::Failed("render panicked".into()),
                    ]),
                ),
                ("g/b".into(), SceneStatus::LoadError("g/b_path.xml:3:5: unknown bsdf 'x'".into())),
                ("participating_media/c".into(), SceneStatus::NoReference),
            ],
        };
        assert_eq!(table.counts(), (3, 1, vec![1, 0], vec![0, 0]));
        let text = table.plain();
        assert!(text.contains("PASS 99.90% ×1.0100 ±0.20% (64 spp)"), "{text}");
        assert!(text.contains("error: render panicked") && text.contains("no reference"), "{text}");
        assert!(text.contains("g/b: g/b_path.xml:3:5: unknown bsdf 'x'"), "{text}");
        assert!(text.contains("3 scenes, 1 load and render; passed: pt 1, vcm 0"), "{text}");
        let provenance = Provenance {
            date: "2026-01-01 00:00 UTC".into(),
            commit: "abc".into(),
            machine: "m".into(),
            command: "vcm conformance x".into(),
            budget: "b".into(),
            reference_spp: 32000.0,
            escalation: 16,
        };
        let md = table.markdown(&provenance, &Criteria::MITSUBA);
        assert!(md.contains("| g/a | yes | PASS 99.90% ×1.0100 ±0.20% (64 spp) | error: render panicked |"), "{md}");
        assert!(md.contains("| g/b | no | - | - |") && md.contains("- commit: abc"), "{md}");
        assert!(md.contains("mitsuba-renderer/mitsuba-data") && md.contains("../../common"), "{md}");
        assert!(md.contains("at 16× the budget"), "the rule names the escalation: {md}");
    }

    #[test]
    fn an_escalated_cell_shows_both_verdicts_and_is_counted() {
        let escalated = Outcome::Judged {
            iterations: 1024,
            verdict: verdict(true, 999),
            first: Some(Box::new(FirstTry { iterations: 64, verdict: verdict(false, 972) })),
        };
        let failed_twice = Outcome::Judged {
            iterations: 1024,
            verdict: verdict(false, 990),
            first: Some(Box::new(FirstTry { iterations: 64, verdict: verdict(false, 972) })),
        };
        let table = Table {
            algorithms: vec!["pt".into(), "vcm".into()],
            rows: vec![("g/a".into(), SceneStatus::Rendered(vec![escalated, failed_twice]))],
        };
        assert_eq!(table.counts(), (1, 1, vec![1, 0], vec![1, 0]));
        let text = table.plain();
        assert!(
            text.contains("PASS 99.90% ×1.0100 ±0.20% (1024 spp; at 64 spp: FAIL 97.20% ×1.0100 ±0.20%)"),
            "{text}"
        );
        assert!(text.contains("FAIL 99.00% ×1.0100 ±0.20% (1024 spp; at 64 spp: FAIL 97.20%"), "{text}");
        assert!(text.contains("passed: pt 1 (1 of them escalated), vcm 0"), "{text}");
    }
}
