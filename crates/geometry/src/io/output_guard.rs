//! [`OutputGuard`]: no command writes over one of its own inputs.
//!
//! Every app builds one guard from the paths its command reads (files, and for a folder input
//! the folder and the files directly in it) and passes each path it is about to write (output
//! files, `--json-out`, `--preview` images, output folders and each file written into them,
//! checkpoints) through [`OutputGuard::check`] before any work. A path is refused when it
//!
//! - is spelled like an input (`scan.obj` and `scan.obj`),
//! - resolves to an input: absolute path, `.`/`..` and symbolic links resolved (for a path that
//!   does not exist yet, its longest existing ancestor is resolved and the rest appended),
//! - or is a hard link to an input (same device and inode, Unix).
//!
//! An output folder is checked like a file: it is refused when it is an input folder, and each
//! file written into it is checked on its own, so a folder that merely holds an input is fine
//! as long as nothing written there lands on it.
//!
//! The check runs before the command reads or computes anything, so a refused command leaves
//! every file as it was; the write itself stays atomic ([`super::atomic_write`]).

use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// The fix named in a refusal when the command has no override.
const CHOOSE_ANOTHER_PATH: &str = "write to another path (inputs are never overwritten)";

/// Device and inode of an existing file: equal for two hard links to the same file.
type FileIdentity = (u64, u64);

/// One path the command reads.
#[derive(Debug, Clone)]
struct Input {
    /// As the user gave it (a file found in an input folder: the folder joined with its name).
    given: PathBuf,
    /// Absolute, `.`/`..` and symbolic links resolved (see [`resolve`]).
    resolved: PathBuf,
    /// Device and inode when the file exists (Unix).
    identity: Option<FileIdentity>,
}

impl Input {
    fn new(given: PathBuf) -> Self {
        Input {
            resolved: resolve(&given),
            identity: identity(&given),
            given,
        }
    }
}

/// The inputs of one command, against which every output path is checked.
///
/// ```
/// use meshgnn_geometry::OutputGuard;
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let dir = tempfile::tempdir()?;
/// let scan = dir.path().join("scan.obj");
/// std::fs::write(&scan, "v 0 0 0\n")?;
/// let guard = OutputGuard::new([&scan]);
/// assert!(guard.check(&dir.path().join("fit.obj")).is_ok());
/// assert!(guard.check(&scan).unwrap_err().to_string().contains("it is the input"));
/// std::fs::create_dir(dir.path().join("sub"))?;
/// let climbing = dir.path().join("sub").join("..").join("scan.obj");
/// let refused = guard.check(&climbing).unwrap_err();
/// assert!(refused.to_string().contains("resolves to the input"));
/// # Ok(()) }
/// ```
#[derive(Debug, Clone)]
pub struct OutputGuard {
    inputs: Vec<Input>,
    fix: String,
}

impl OutputGuard {
    /// A guard over `inputs`: files, and folders (the folder and the files directly in it).
    /// Paths that do not exist are kept as spelled and resolved as far as they exist: the
    /// command's own read reports them.
    pub fn new<P: AsRef<Path>>(inputs: impl IntoIterator<Item = P>) -> Self {
        let mut guarded = Vec::new();
        for input in inputs {
            let input = input.as_ref();
            guarded.push(Input::new(input.to_path_buf()));
            if input.is_dir() {
                add_folder_files(input, &mut guarded);
            }
        }
        OutputGuard {
            inputs: guarded,
            fix: CHOOSE_ANOTHER_PATH.to_owned(),
        }
    }

    /// The same guard, whose refusals name `flag` as the way to overwrite anyway (for a
    /// command such as `meshsimplify simplify --force`; the command builds the guard without
    /// the input when the flag is given).
    pub fn overridable_by(mut self, flag: &str) -> Self {
        self.fix = format!("write to another path, or pass {flag} to overwrite it");
        self
    }

    /// `output` itself when writing it (a file, or a folder to create and fill) replaces no
    /// input; otherwise [`Error::OutputIsInput`] naming the output, the input, how they are
    /// the same file and the fix.
    pub fn check<'a>(&self, output: &'a Path) -> Result<&'a Path> {
        let resolved = resolve(output);
        let output_identity = identity(output);
        for input in &self.inputs {
            let relation = if output == input.given {
                "is"
            } else if resolved == input.resolved {
                "resolves to"
            } else if output_identity.is_some() && output_identity == input.identity {
                "is a hard link to"
            } else {
                continue;
            };
            return Err(Error::OutputIsInput {
                output: output.to_path_buf(),
                input: input.given.clone(),
                relation,
                fix: self.fix.clone(),
            });
        }
        Ok(output)
    }
}

/// Adds every file directly in `folder`, as the commands read folders (dataset names and
/// bench inputs are plain file names; subfolders are not read, so they are not inputs).
/// Unreadable entries are skipped: the command reports them when it reads them.
fn add_folder_files(folder: &Path, guarded: &mut Vec<Input>) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if !path.is_dir() {
            guarded.push(Input::new(path));
        }
    }
}

/// `path` made absolute with `.`, `..` and symbolic links resolved as far as it exists; the
/// components after the first missing one are appended lexically (a missing folder followed by
/// `..` cannot be opened anyway). Resolving component by component keeps `..` physical: it
/// pops the resolved target of a link, as the operating system does.
fn resolve(path: &Path) -> PathBuf {
    let Ok(absolute) = std::path::absolute(path) else {
        return path.to_path_buf();
    };
    let mut resolved = PathBuf::new();
    let mut exists = true;
    for component in absolute.components() {
        match component {
            Component::Prefix(_) | Component::RootDir => resolved.push(component),
            Component::CurDir => {}
            Component::ParentDir => {
                resolved.pop();
            }
            Component::Normal(name) => {
                resolved.push(name);
                if exists {
                    match resolved.canonicalize() {
                        Ok(canonical) => resolved = canonical,
                        Err(_) => exists = false,
                    }
                }
            }
        }
    }
    resolved
}

/// Device and inode of the file `path` names (links followed), when it exists.
#[cfg(unix)]
fn identity(path: &Path) -> Option<FileIdentity> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// Hard links are not detected off Unix; resolved paths still are.
#[cfg(not(unix))]
fn identity(_path: &Path) -> Option<FileIdentity> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A folder holding `scan.obj`, `data/mesh.obj` and `data/sub/mesh.obj` (a subfolder is
    /// not read), and the guard over the scan and the data folder.
    fn setup() -> (tempfile::TempDir, OutputGuard) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("scan.obj"), "v 0 0 0\n").unwrap();
        std::fs::create_dir(dir.path().join("data")).unwrap();
        std::fs::write(dir.path().join("data/mesh.obj"), "v 0 0 0\n").unwrap();
        std::fs::create_dir(dir.path().join("data/sub")).unwrap();
        std::fs::write(dir.path().join("data/sub/mesh.obj"), "v 0 0 0\n").unwrap();
        let guard = OutputGuard::new([dir.path().join("scan.obj"), dir.path().join("data")]);
        (dir, guard)
    }

    fn relation(guard: &OutputGuard, output: &Path) -> Option<&'static str> {
        match guard.check(output) {
            Ok(_) => None,
            Err(Error::OutputIsInput { relation, .. }) => Some(relation),
            Err(other) => panic!("unexpected error {other}"),
        }
    }

    #[test]
    fn the_input_path_itself_is_refused_naming_both_and_the_fix() {
        let (dir, guard) = setup();
        let scan = dir.path().join("scan.obj");
        let message = guard.check(&scan).unwrap_err().to_string();
        assert_eq!(
            message,
            format!(
                "refusing to write {0}: it is the input {0}; {1}",
                scan.display(),
                CHOOSE_ANOTHER_PATH
            )
        );
        assert!(!message.contains('\n'));
    }

    #[test]
    fn dot_and_dot_dot_spellings_resolve_to_the_input() {
        let (dir, guard) = setup();
        let dotted = dir
            .path()
            .join(".")
            .join("data")
            .join("..")
            .join("scan.obj");
        assert_eq!(relation(&guard, &dotted), Some("resolves to"));
        // a relative spelling, resolved against the current directory
        let cwd = std::env::current_dir().unwrap();
        let relative = pathdiff(&cwd, &dir.path().join("data"))
            .join("..")
            .join("scan.obj");
        assert!(relative.is_relative());
        assert_eq!(relation(&guard, &relative), Some("resolves to"));
    }

    /// `to` spelled relative to `from` with `..` (both absolute).
    fn pathdiff(from: &Path, to: &Path) -> PathBuf {
        let from: Vec<_> = from.components().collect();
        let to: Vec<_> = to.components().collect();
        let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
        let mut path = PathBuf::new();
        for _ in common..from.len() {
            path.push("..");
        }
        for component in &to[common..] {
            path.push(component);
        }
        path
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_to_the_input_and_a_path_through_a_linked_folder_are_refused() {
        let (dir, guard) = setup();
        let link = dir.path().join("link.obj");
        std::os::unix::fs::symlink(dir.path().join("scan.obj"), &link).unwrap();
        assert_eq!(relation(&guard, &link), Some("resolves to"));
        let linked_folder = dir.path().join("elsewhere");
        std::os::unix::fs::symlink(dir.path().join("data"), &linked_folder).unwrap();
        assert_eq!(
            relation(&guard, &linked_folder.join("mesh.obj")),
            Some("resolves to")
        );
        // `..` after a link leaves the link's target, as the kernel does: data/.. is dir
        assert_eq!(
            relation(&guard, &linked_folder.join("..").join("scan.obj")),
            Some("resolves to")
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_hard_link_to_the_input_is_refused() {
        let (dir, guard) = setup();
        let hard = dir.path().join("hard.obj");
        std::fs::hard_link(dir.path().join("scan.obj"), &hard).unwrap();
        assert_eq!(relation(&guard, &hard), Some("is a hard link to"));
    }

    #[test]
    fn an_input_folder_and_the_files_in_it_are_refused_as_outputs() {
        let (dir, guard) = setup();
        assert_eq!(relation(&guard, &dir.path().join("data")), Some("is"));
        assert_eq!(
            relation(&guard, &dir.path().join("data/mesh.obj")),
            Some("is")
        );
        let message = guard
            .check(&dir.path().join("data/./mesh.obj"))
            .unwrap_err()
            .to_string();
        assert!(message.contains("mesh.obj"), "{message}");
    }

    #[test]
    fn distinct_outputs_are_accepted_even_beside_or_inside_an_input_folder() {
        let (dir, guard) = setup();
        for output in [
            dir.path().join("fit.obj"),
            dir.path().join("data/report.json"),
            dir.path().join("data/sub/mesh.obj"),
            dir.path().join("new/folder/out.obj"),
            dir.path().join("missing/../fit.obj"),
            dir.path().to_path_buf(),
        ] {
            assert_eq!(relation(&guard, &output), None, "{}", output.display());
        }
    }

    #[test]
    fn a_missing_input_is_still_guarded_by_its_spelling() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.obj");
        let guard = OutputGuard::new([&missing]);
        assert_eq!(relation(&guard, &missing), Some("is"));
        assert_eq!(
            relation(&guard, &dir.path().join("absent/../missing.obj")),
            Some("resolves to")
        );
    }

    #[test]
    fn an_override_flag_is_named_in_the_fix() {
        let (dir, guard) = setup();
        let guard = guard.overridable_by("--force");
        let message = guard
            .check(&dir.path().join("scan.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            message.ends_with("or pass --force to overwrite it"),
            "{message}"
        );
    }
}
