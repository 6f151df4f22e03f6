//! Transparent huge pages for the heap: `vcm` starts itself again with glibc's tunable
//! `glibc.malloc.hugetlb=1`, which makes `malloc` ask the kernel (`madvise(MADV_HUGEPAGE)`) for
//! 2 MiB pages on the memory it maps. The BVH, the primitive records and the light vertices are
//! read at random; with 4 KiB pages nearly every such read also misses the TLB. Measured gains
//! and the switch (`VCM_HUGE_PAGES=0`) are in `docs/bvh.md` ("The hit's attributes and huge
//! pages"). The images do not change: only where the memory lies does.
//!
//! Tunables are read by glibc when a process starts, so setting the variable from inside the
//! process is too late; hence the one `exec` before anything else runs. It happens only on
//! Linux with glibc, only when `GLIBC_TUNABLES` does not already name the tunable (so the
//! second start goes on, and a user's own setting wins), never when `VCM_HUGE_PAGES=0`, and
//! never under valgrind, which does not follow an `exec` (the profiling commands in the docs
//! would count only the start): valgrind preloads its `vgpreload_*` libraries.

use std::ffi::{OsStr, OsString};

/// The environment variable that switches the re-start off (`0`) or on (`1`, the default).
pub const HUGE_PAGES_ENV: &str = "VCM_HUGE_PAGES";

/// glibc's variable of tunables (a colon-separated list of `name=value`).
const TUNABLES_ENV: &str = "GLIBC_TUNABLES";

/// The tunable that asks for transparent huge pages on the heap (glibc ≥ 2.35; older glibc
/// ignores names it does not know).
const HUGETLB: &str = "glibc.malloc.hugetlb";

/// The value `GLIBC_TUNABLES` should have in the re-started process, or `None` when `vcm`
/// should go on as it is: the switch is `0`, the tunables already name [`HUGETLB`], or
/// `LD_PRELOAD` (`preload`) names valgrind's libraries. An error for a switch other than `0`
/// or `1`.
fn tunables_to_set(
    tunables: Option<&OsStr>,
    switch: Option<&OsStr>,
    preload: Option<&OsStr>,
) -> Result<Option<OsString>, String> {
    match switch.map(|s| s.to_str()) {
        None | Some(Some("1")) => {}
        Some(Some("0")) => return Ok(None),
        Some(_) => {
            let value = switch.unwrap_or_default();
            return Err(format!("{HUGE_PAGES_ENV}={value:?}: expected 0 (off) or 1 (on, the default)"));
        }
    }
    if preload.is_some_and(|p| p.to_string_lossy().contains("vgpreload")) {
        return Ok(None);
    }
    let existing = tunables.unwrap_or_default();
    let named = existing
        .to_string_lossy()
        .split(':')
        .any(|entry| entry.split('=').next().is_some_and(|name| name.trim() == HUGETLB));
    if named {
        return Ok(None);
    }
    let mut value = existing.to_os_string();
    if !value.is_empty() {
        value.push(":");
    }
    value.push(format!("{HUGETLB}=1"));
    Ok(Some(value))
}

/// Starts `vcm` again with huge pages for the heap when it should (see the module's docs);
/// returns only when it does not, or when the re-start failed (then `vcm` goes on with normal
/// pages: the image is the same). An error for a bad [`HUGE_PAGES_ENV`].
pub fn restart_with_huge_pages() -> Result<(), String> {
    let set = tunables_to_set(
        std::env::var_os(TUNABLES_ENV).as_deref(),
        std::env::var_os(HUGE_PAGES_ENV).as_deref(),
        std::env::var_os("LD_PRELOAD").as_deref(),
    )?;
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if let Some(tunables) = set
        && let Ok(exe) = std::env::current_exe()
    {
        use std::os::unix::process::CommandExt;
        let error =
            std::process::Command::new(exe).args(std::env::args_os().skip(1)).env(TUNABLES_ENV, tunables).exec();
        eprintln!("note: could not start again with huge pages ({error}); going on without them");
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    let _ = set;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(tunables: Option<&str>, switch: Option<&str>) -> Result<Option<String>, String> {
        tunables_to_set(tunables.map(OsStr::new), switch.map(OsStr::new), None)
            .map(|v| v.map(|v| v.into_string().expect("unicode")))
    }

    #[test]
    fn the_tunable_is_added_unless_it_is_set_switched_off_or_under_valgrind() {
        let on = Some("glibc.malloc.hugetlb=1".to_string());
        assert_eq!(set(None, None), Ok(on.clone()));
        assert_eq!(set(Some(""), Some("1")), Ok(on));
        assert_eq!(
            set(Some("glibc.malloc.arena_max=2"), None),
            Ok(Some("glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1".to_string()))
        );
        // Already named (the re-started process, or the user's own choice): go on as it is.
        assert_eq!(set(Some("glibc.malloc.hugetlb=1"), None), Ok(None));
        assert_eq!(set(Some("glibc.malloc.arena_max=2:glibc.malloc.hugetlb=0"), None), Ok(None));
        // Switched off.
        assert_eq!(set(None, Some("0")), Ok(None));
        // Under valgrind (its preloaded libraries), which would not follow the exec.
        let valgrind = OsStr::new("/usr/libexec/valgrind/vgpreload_core-amd64-linux.so");
        assert_eq!(tunables_to_set(None, None, Some(valgrind)), Ok(None));
        assert_eq!(
            tunables_to_set(None, None, Some(OsStr::new("libother.so"))),
            Ok(Some(OsString::from("glibc.malloc.hugetlb=1")))
        );
        // Anything else is an error naming the values it may take.
        let error = set(None, Some("yes")).expect_err("bad switch");
        assert!(error.contains("VCM_HUGE_PAGES") && error.contains("expected 0"), "{error}");
    }
}
