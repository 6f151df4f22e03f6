//! Where and when a conformance run was made: UTC date, the source's commit, the machine and the
//! command line, for the Markdown document.

use super::table::Provenance;

/// Collects the provenance of the current run; `budget` describes the per-render budget.
pub fn collect(budget: &str, reference_spp: f64, escalation: u64) -> Provenance {
    Provenance {
        date: utc_now(),
        commit: commit(),
        machine: machine(),
        command: std::env::args().collect::<Vec<_>>().join(" "),
        budget: budget.to_string(),
        reference_spp,
        escalation,
    }
}

/// `YYYY-MM-DD HH:MM UTC` of now.
fn utc_now() -> String {
    let seconds = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    format_utc(seconds)
}

/// `YYYY-MM-DD HH:MM UTC` of a Unix time, by the proleptic Gregorian calendar (days counted in
/// 400-year eras of 146097 days, years starting on 1 March so that the leap day is last).
fn format_utc(unix_seconds: u64) -> String {
    let days = (unix_seconds / 86_400) as i64;
    let minutes_of_day = (unix_seconds % 86_400) / 60;
    // Days since 0000-03-01.
    let shifted = days + 719_468;
    let era = shifted.div_euclid(146_097);
    let day_of_era = shifted.rem_euclid(146_097);
    let year_of_era = (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let month_from_march = (5 * day_of_year + 2) / 153;
    let day = day_of_year - (153 * month_from_march + 2) / 5 + 1;
    let month = if month_from_march < 10 { month_from_march + 3 } else { month_from_march - 9 };
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {:02}:{:02} UTC", minutes_of_day / 60, minutes_of_day % 60)
}

/// The short commit hash of the working directory's repository, `-dirty` when it has
/// uncommitted changes to tracked files; "unknown" outside a repository.
fn commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short", "HEAD"]) {
        Some(hash) => {
            let dirty = git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
            if dirty { format!("{hash}-dirty") } else { hash }
        }
        None => "unknown".to_string(),
    }
}

/// CPU model, logical cores and memory, from `/proc` where it exists.
fn machine() -> String {
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let field = |file: &str, key: &str| {
        std::fs::read_to_string(file).ok().and_then(|text| {
            text.lines().find(|l| l.starts_with(key)).and_then(|l| l.split(':').nth(1)).map(|v| v.trim().to_string())
        })
    };
    let cpu = field("/proc/cpuinfo", "model name").unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let memory = field("/proc/meminfo", "MemTotal")
        .and_then(|v| v.split_whitespace().next().and_then(|k| k.parse::<f64>().ok()))
        .map(|kib| format!(", {:.1} GiB memory", kib / 1_048_576.0))
        .unwrap_or_default();
    format!("{cpu}, {cores} logical cores{memory}, {}", std::env::consts::OS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_match_known_instants() {
        assert_eq!(format_utc(0), "1970-01-01 00:00 UTC");
        // 2000-02-29 12:34 UTC (a leap day of a year divisible by 400).
        assert_eq!(format_utc(951_827_640), "2000-02-29 12:34 UTC");
        // 2026-11-24 04:16 UTC.
        assert_eq!(format_utc(1_795_493_760), "2026-11-24 04:16 UTC");
    }
}
