//! The outputs of `vcm conformance`: the plain-text table for stdout and the Markdown document
//! (the same table with the run's provenance, the rule and how to fetch the suite).

use std::fmt::Write as _;

use super::verdict::{Criteria, Verdict};

/// What happened to one scene.
#[derive(Clone, Debug)]
pub enum SceneStatus {
    /// The scene needs participating media; not rendered.
    NeedsMedia,
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
    /// Rendered with this many iterations (samples per pixel) and judged.
    Judged { iterations: u64, verdict: Verdict },
    /// Rendering or comparing failed (or panicked): the first line of the error.
    Failed(String),
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
    /// Counts `(scenes, loaded, passed per algorithm)`.
    pub fn counts(&self) -> (usize, usize, Vec<usize>) {
        let mut loaded = 0;
        let mut passed = vec![0; self.algorithms.len()];
        for (_, status) in &self.rows {
            if let SceneStatus::Rendered(outcomes) = status {
                loaded += 1;
                for (count, outcome) in passed.iter_mut().zip(outcomes) {
                    if matches!(outcome, Outcome::Judged { verdict, .. } if verdict.passed) {
                        *count += 1;
                    }
                }
            }
        }
        (self.rows.len(), loaded, passed)
    }

    /// Rows as cells: scene, loads, one per algorithm.
    fn cells(&self) -> Vec<Vec<String>> {
        self.rows
            .iter()
            .map(|(label, status)| {
                let mut row = vec![label.clone()];
                match status {
                    SceneStatus::NeedsMedia => row.push("needs media".into()),
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
        let (scenes, loaded, passed) = self.counts();
        let passes: Vec<String> = self.algorithms.iter().zip(&passed).map(|(a, p)| format!("{a} {p}")).collect();
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
             per-sample variance divided by the reference's sample count ({}); entries whose variances \
             are both zero get `vcm compare`'s floor of {} of the value. An entry passes when its \
             two-sided p-value is at least the Šidák level 1 − (1 − α)^(1/n) with α = {} over the n \
             pixel channels. A cell reads PASS iff at least {} % of the entries pass **and** every \
             channel's image mean is within {} % of the reference's; it shows the fraction of passing \
             entries and the channel mean ratio (render / reference) farthest from 1, with the \
             samples per pixel.\n",
            provenance.reference_spp,
            criteria.relative_floor,
            criteria.alpha,
            100.0 * criteria.pass_fraction,
            100.0 * criteria.mean_tolerance
        );
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
             (`mitsuba-data/tests/common` must sit beside `mitsuba-data/tests/scenes`.) The \
             `participating_media` scenes need media, which the renderer does not have; they are \
             listed, not rendered."
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
}

/// One algorithm's cell: `PASS 99.96% ×1.0021 (868 spp)`.
fn cell(outcome: &Outcome) -> String {
    match outcome {
        Outcome::Judged { iterations, verdict } => format!(
            "{} {:.2}% ×{:.4} ({iterations} spp)",
            if verdict.passed { "PASS" } else { "FAIL" },
            100.0 * verdict.pass_fraction(),
            verdict.worst_mean_ratio()
        ),
        Outcome::Failed(error) => format!("error: {error}"),
    }
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
                        Outcome::Judged { iterations: 64, verdict: verdict(true, 999) },
                        Outcome::Failed("render panicked".into()),
                    ]),
                ),
                ("g/b".into(), SceneStatus::LoadError("g/b_path.xml:3:5: unknown bsdf 'x'".into())),
                ("participating_media/c".into(), SceneStatus::NeedsMedia),
            ],
        };
        assert_eq!(table.counts(), (3, 1, vec![1, 0]));
        let text = table.plain();
        assert!(text.contains("PASS 99.90% ×1.0100 (64 spp)"), "{text}");
        assert!(text.contains("error: render panicked") && text.contains("needs media"), "{text}");
        assert!(text.contains("g/b: g/b_path.xml:3:5: unknown bsdf 'x'"), "{text}");
        assert!(text.contains("3 scenes, 1 load and render; passed: pt 1, vcm 0"), "{text}");
        let provenance = Provenance {
            date: "2026-01-01 00:00 UTC".into(),
            commit: "abc".into(),
            machine: "m".into(),
            command: "vcm conformance x".into(),
            budget: "b".into(),
            reference_spp: 32000.0,
        };
        let md = table.markdown(&provenance, &Criteria::MITSUBA);
        assert!(md.contains("| g/a | yes | PASS 99.90% ×1.0100 (64 spp) | error: render panicked |"), "{md}");
        assert!(md.contains("| g/b | no | - | - |") && md.contains("- commit: abc"), "{md}");
        assert!(md.contains("mitsuba-renderer/mitsuba-data") && md.contains("../../common"), "{md}");
    }
}
