//! Atomic file output: every writer of meshgnn goes through [`atomic_write`].
//!
//! The bytes go to a temporary file `.NAME.tmp-PID-N` in the destination's directory, are
//! flushed to disk, and the temporary file is renamed over the destination. A reader never
//! sees a half-written file, a crash leaves the old file intact, and only the path named as the
//! output changes.
//!
//! # Temporary files never outlive their run
//! - On an error the temporary file is removed before the error is returned.
//! - Every temporary file is listed, while it exists, in one process-wide registry. An app
//!   calls [`remove_temporaries_on_interrupt`] once at start: on SIGINT (Ctrl-C), SIGTERM or
//!   SIGHUP the listed files are removed and the process exits with status 130. Creating and
//!   renaming a temporary file hold the registry's lock, so an interrupt either removes a
//!   temporary file or finds it already renamed into place: the output path is complete or
//!   absent, never partial, and no temporary file is left.
//! - A run that was killed without a chance to clean up (SIGKILL, power loss) leaves its
//!   temporary files behind. The first write into a folder removes the temporary files of
//!   that pattern whose process is gone (no `/proc/PID` on Linux; elsewhere, untouched for a
//!   day) and says so in one line on stderr.
//!
//! The signal handler comes from the `ctrlc` crate (feature `termination` for SIGTERM and
//! SIGHUP): it installs the handler with `sigaction` and runs the closure on an ordinary
//! thread woken through a pipe, so the cleanup may lock, allocate and print, which a raw
//! signal handler may not, and it keeps `unsafe` out of this workspace.

use crate::error::{Error, Result};
use std::collections::BTreeSet;
use std::ffi::OsString;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};
use std::time::Duration;

/// Distinguishes temporary files of concurrent writes from one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files of this process that exist right now.
static LIVE: Mutex<Registry> = Mutex::new(Registry::new());

/// Folders already cleared of stale temporary files by this process.
static SWEPT: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

/// Where no `/proc` tells whether a process lives, a temporary file untouched this long is
/// taken as left by a dead run.
const STALE_AGE: Duration = Duration::from_secs(24 * 60 * 60);

/// Writes `bytes` to `path` atomically (temporary file in the same directory, fsync, rename).
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("notes.txt");
/// meshgnn_geometry::atomic_write(&path, b"first")?;
/// meshgnn_geometry::atomic_write(&path, b"second")?;
/// assert_eq!(std::fs::read(&path)?, b"second");
/// assert_eq!(std::fs::read_dir(dir.path())?.count(), 1); // no temporary file left
/// # Ok(()) }
/// ```
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<()> {
    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        error: source,
    };
    let name = path.file_name().ok_or_else(|| {
        io_error(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "output path has no file name",
        ))
    })?;
    let directory = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    remove_stale_temporaries(&directory);
    let temporary = directory.join(temporary_name(
        name,
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed),
    ));
    // the lock is held to create and to rename, not while the bytes are written
    let created = lock(&LIVE).create(&temporary);
    let written = created.and_then(|mut file| {
        file.write_all(bytes)?;
        file.sync_all()
    });
    let renamed = written.and_then(|()| lock(&LIVE).rename(&temporary, path));
    if let Err(source) = renamed {
        lock(&LIVE).discard(&temporary);
        return Err(io_error(source));
    }
    Ok(())
}

/// Installs the handler that, on SIGINT, SIGTERM or SIGHUP, removes this process's live
/// temporary files, prints one line on stderr and exits with status 130. Call it once, at the
/// start of `main`; a second call fails (the operating system keeps one handler).
pub fn remove_temporaries_on_interrupt() -> std::io::Result<()> {
    ctrlc::set_handler(|| {
        let removed = remove_live_temporaries();
        match removed {
            0 => eprintln!("interrupted"),
            n => eprintln!("interrupted: removed {n} unfinished temporary file(s)"),
        }
        std::process::exit(130);
    })
    .map_err(|error| match error {
        ctrlc::Error::System(error) => error,
        other => std::io::Error::other(other),
    })
}

/// Removes this process's live temporary files and refuses new ones, for a process about to
/// exit early; returns how many were removed.
pub(crate) fn remove_live_temporaries() -> usize {
    lock(&LIVE).interrupt()
}

/// `.NAME.tmp-PID-N`: hidden, beside the output, naming the process that owns it.
fn temporary_name(name: &std::ffi::OsStr, pid: u32, counter: u64) -> OsString {
    let mut temporary = OsString::from(".");
    temporary.push(name);
    temporary.push(format!(".tmp-{pid}-{counter}"));
    temporary
}

/// The PID in a file name of the form [`temporary_name`] writes, `None` for any other name.
fn temporary_pid(name: &str) -> Option<u32> {
    let (stem, suffix) = name.strip_prefix('.')?.rsplit_once(".tmp-")?;
    let (pid, counter) = suffix.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if stem.is_empty() || !digits(pid) || !digits(counter) {
        return None;
    }
    pid.parse().ok()
}

/// Removes, once per folder and process, the temporary files in `directory` left by runs
/// that are gone, and reports them in one line on stderr. Best effort: a folder that cannot
/// be listed is left alone (the write itself reports why it fails).
fn remove_stale_temporaries(directory: &Path) {
    if !lock(&SWEPT).insert(directory.to_path_buf()) {
        return;
    }
    let Ok(entries) = std::fs::read_dir(directory) else {
        return;
    };
    let own = std::process::id();
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temporary_pid) else {
            continue;
        };
        if pid != own && is_stale(pid, &entry) && std::fs::remove_file(entry.path()).is_ok() {
            removed.push(name.to_string_lossy().into_owned());
        }
    }
    if !removed.is_empty() {
        eprintln!(
            "removed {} stale temporary file(s) of interrupted runs from {}: {}",
            removed.len(),
            directory.display(),
            removed.join(", ")
        );
    }
}

/// Whether the temporary file `entry` of process `pid` was left by a run that is gone.
fn is_stale(pid: u32, entry: &std::fs::DirEntry) -> bool {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        return !Path::new("/proc").join(pid.to_string()).exists();
    }
    entry
        .metadata()
        .and_then(|m| m.modified())
        .ok()
        .and_then(|modified| modified.elapsed().ok())
        .is_some_and(|age| age > STALE_AGE)
}

/// Locks a registry; a thread that panicked while holding it left it consistent (each method
/// changes it with one call), so a poisoned lock is used as it is.
fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

/// The temporary files that exist, and whether the process is being interrupted.
#[derive(Debug)]
struct Registry {
    paths: Vec<PathBuf>,
    interrupted: bool,
}

impl Registry {
    const fn new() -> Self {
        Registry {
            paths: Vec::new(),
            interrupted: false,
        }
    }

    /// Creates `temporary` (never an existing file) and lists it; refused once interrupted.
    fn create(&mut self, temporary: &Path) -> std::io::Result<std::fs::File> {
        if self.interrupted {
            return Err(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "interrupted before writing",
            ));
        }
        let file = std::fs::File::create_new(temporary)?;
        self.paths.push(temporary.to_path_buf());
        Ok(file)
    }

    /// Renames `temporary` over `path` and unlists it.
    fn rename(&mut self, temporary: &Path, path: &Path) -> std::io::Result<()> {
        std::fs::rename(temporary, path)?;
        self.paths.retain(|p| p != temporary);
        Ok(())
    }

    /// Removes `temporary` (best effort: it may not exist) and unlists it.
    fn discard(&mut self, temporary: &Path) {
        let _ = std::fs::remove_file(temporary);
        self.paths.retain(|p| p != temporary);
    }

    /// Removes every listed file, refuses new ones, and returns how many were removed.
    fn interrupt(&mut self) -> usize {
        self.interrupted = true;
        self.paths
            .drain(..)
            .filter(|p| std::fs::remove_file(p).is_ok())
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_content_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        atomic_write(&path, b"first").unwrap();
        atomic_write(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(entries.len(), 1);
    }

    #[test]
    fn missing_directory_is_an_io_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("no/such/dir/out.txt");
        let err = atomic_write(&path, b"x").unwrap_err();
        assert!(matches!(err, Error::Io { path: p, .. } if p == path));
    }

    #[test]
    fn a_failed_rename_removes_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        // renaming a file over a non-empty folder fails
        let path = dir.path().join("taken");
        std::fs::create_dir(&path).unwrap();
        std::fs::write(path.join("inside"), b"x").unwrap();
        assert!(atomic_write(&path, b"bytes").is_err());
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["taken"]);
    }

    #[test]
    fn temporary_names_carry_the_pid_and_are_recognised() {
        let name = temporary_name("out.obj".as_ref(), 4242, 7);
        assert_eq!(name, ".out.obj.tmp-4242-7");
        assert_eq!(temporary_pid(".out.obj.tmp-4242-7"), Some(4242));
        assert_eq!(temporary_pid(".a.tmp-b.tmp-12-0"), Some(12));
        for other in [
            "out.obj.tmp-1-0",
            "..tmp-1-0",
            ".out.obj.tmp-1-",
            ".out.obj.tmp--0",
            ".out.obj.tmp-+1-0",
            ".out.obj.tmp-1-0.bak",
            ".out.obj",
        ] {
            assert_eq!(temporary_pid(other), None, "{other}");
        }
    }

    /// The PID of a process that has exited (and been reaped).
    fn dead_pid() -> u32 {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        pid
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn stale_temporaries_of_dead_runs_are_removed_and_live_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let stale = dir.path().join(format!(".out.obj.tmp-{}-0", dead_pid()));
        let own = dir
            .path()
            .join(format!(".out.obj.tmp-{}-999", std::process::id()));
        let init = dir.path().join(".out.obj.tmp-1-0");
        let unrelated = dir.path().join(".out.obj.tmp-x");
        for path in [&stale, &own, &init, &unrelated] {
            std::fs::write(path, b"partial").unwrap();
        }
        atomic_write(&dir.path().join("out.obj"), b"done").unwrap();
        assert!(!stale.exists());
        assert!(own.exists() && init.exists() && unrelated.exists());
    }

    #[test]
    fn an_interrupted_registry_removes_its_files_and_refuses_new_ones() {
        let dir = tempfile::tempdir().unwrap();
        let mut registry = Registry::new();
        let a = dir.path().join(".a.tmp-1-0");
        let b = dir.path().join(".b.tmp-1-1");
        registry.create(&a).unwrap();
        registry.create(&b).unwrap();
        registry
            .rename(&b, &dir.path().join("b"))
            .expect("renamed into place");
        assert_eq!(registry.interrupt(), 1);
        assert!(!a.exists() && dir.path().join("b").exists());
        let err = registry.create(&dir.path().join(".c.tmp-1-2")).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::Interrupted);
        assert!(!dir.path().join(".c.tmp-1-2").exists());
    }
}
