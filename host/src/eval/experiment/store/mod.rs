//! Finished experiment runs kept on disk, so that an interrupted `sndt experiment` can
//! continue where it stopped (`--resume`) instead of starting from zero.
//!
//! A store is a directory (`<out>/runs/`) of small JSON files, each written atomically
//! ([`crate::atomic`]) as soon as its run is finished: a crash or a kill leaves
//! every file either whole or absent. Beside them, `manifest.json` records the options the
//! runs were made with; a store is only resumed under the same options. What a file holds
//! is the business of `records.rs` beside this file, which knows the experiment's runs
//! ([`RunStore::save_result`] takes any serialisable value): this module knows names, the
//! manifest, the counts and the test hook only, so that the directory's guarantees (whole
//! files, same options, the stop hook) are checked in one place.

pub(super) mod records;

use crate::atomic::write_bytes;
use anyhow::{bail, Context, Result};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// The options a store's runs were made with: option name (as the command line spells it,
/// so that a refusal names it) to its value as text.
pub type Manifest = BTreeMap<String, String>;

/// Name of the manifest inside the store.
pub const MANIFEST: &str = "manifest.json";

/// Exit code of the process stopped by the test hook `SNDT_EXPERIMENT_STOP_AFTER`.
pub const STOP_EXIT_CODE: i32 = 86;

/// The manifest file's content: a format tag, so that a later layout is told apart.
#[derive(Serialize, serde::Deserialize)]
struct ManifestFile {
    format: String,
    options: Manifest,
}

const FORMAT: &str = "sndt experiment runs 1";

/// A directory of finished runs.
pub struct RunStore {
    dir: PathBuf,
    /// Held while a file is written and counted, so that the test hook stops the process
    /// with exactly its number of results on disk (no other write completes meanwhile).
    writing: Mutex<()>,
    computed: AtomicUsize,
    resumed: AtomicUsize,
    stop_after: Option<usize>,
}

impl RunStore {
    /// Opens the store `dir` for runs made with `manifest`.
    ///
    /// Without `resume` the store starts afresh: the result files of an earlier run
    /// (`*.json` and unfinished temporary files) are removed and `manifest` is written.
    /// With `resume`, a store made with other options is refused, naming the manifest and
    /// each option that differs; a missing store starts afresh (with a note on stderr).
    pub fn open(dir: &Path, manifest: &Manifest, resume: bool) -> Result<RunStore> {
        let path = dir.join(MANIFEST);
        let fresh = !resume || !path.exists();
        if resume && fresh {
            eprintln!(
                "nothing to resume: {} does not exist; starting afresh",
                path.display()
            );
        }
        if fresh {
            clear(dir)?;
            let file = ManifestFile {
                format: FORMAT.into(),
                options: manifest.clone(),
            };
            write_bytes(&path, serde_json::to_string_pretty(&file)? + "\n")?;
        } else {
            check_manifest(&path, manifest)?;
        }
        Ok(RunStore {
            dir: dir.to_path_buf(),
            writing: Mutex::new(()),
            computed: AtomicUsize::new(0),
            resumed: AtomicUsize::new(0),
            stop_after: stop_after(),
        })
    }

    /// The store's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The stored value `name`, made into a `U` by `convert`. A file that cannot be read
    /// or parsed, or that `convert` rejects (its reason returned as `Err`), is reported on
    /// stderr naming the file and treated as absent, so that its run is recomputed (and
    /// the file replaced) rather than the experiment stopped or silently wrong.
    pub fn load<T: DeserializeOwned, U>(
        &self,
        name: &str,
        convert: impl FnOnce(T) -> std::result::Result<U, String>,
    ) -> Option<U> {
        let path = self.dir.join(name);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return None,
            Err(e) => return warn(&path, &e.to_string()),
        };
        let value: T = match serde_json::from_slice(&bytes) {
            Ok(v) => v,
            Err(e) => return warn(&path, &format!("not a valid stored run ({e})")),
        };
        match convert(value) {
            Ok(v) => Some(v),
            Err(why) => warn(&path, &why),
        }
    }

    /// Stores `value` as `name`, not counted as a result (e.g. what several results share).
    pub fn save<T: Serialize>(&self, name: &str, value: &T) -> Result<()> {
        let _guard = self.writing.lock().unwrap_or_else(PoisonError::into_inner);
        write_bytes(&self.dir.join(name), encode(value)?)
    }

    /// Stores the finished result `name` and counts it as computed.
    pub fn save_result<T: Serialize>(&self, name: &str, value: &T) -> Result<()> {
        let _guard = self.writing.lock().unwrap_or_else(PoisonError::into_inner);
        write_bytes(&self.dir.join(name), encode(value)?)?;
        let n = self.computed.fetch_add(1, Ordering::SeqCst) + 1;
        if self.stop_after == Some(n) {
            // Still holding `writing`: no other result reaches the disk before the exit.
            eprintln!("SNDT_EXPERIMENT_STOP_AFTER: stopping after {n} results");
            std::process::exit(STOP_EXIT_CODE);
        }
        Ok(())
    }

    /// Counts a result taken from the store instead of computed.
    pub fn count_resumed(&self) {
        self.resumed.fetch_add(1, Ordering::SeqCst);
    }

    /// Results taken from the store so far.
    pub fn resumed(&self) -> usize {
        self.resumed.load(Ordering::SeqCst)
    }

    /// Results computed (and stored) so far.
    pub fn computed(&self) -> usize {
        self.computed.load(Ordering::SeqCst)
    }
}

/// One line of compact JSON: results are read back by sndt, not by people, and a
/// confusion matrix spread one number per line would be thousands of lines.
fn encode<T: Serialize>(value: &T) -> Result<Vec<u8>> {
    let mut bytes = serde_json::to_vec(value)?;
    bytes.push(b'\n');
    Ok(bytes)
}

/// Reports an unusable stored file; its run will be recomputed.
fn warn<T>(path: &Path, why: &str) -> Option<T> {
    eprintln!("warning: {}: {why}; recomputing it", path.display());
    None
}

/// Removes what an earlier run left in `dir` (its `*.json` files and unfinished temporary
/// files; nothing else), creating `dir` if needed.
fn clear(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let entries = std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
    for entry in entries {
        let path = entry?.path();
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        let ours = name.ends_with(".json") || (name.starts_with('.') && name.contains(".tmp-"));
        if ours && path.is_file() {
            std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
        }
    }
    Ok(())
}

/// Refuses to resume from `path` unless it records exactly `manifest`.
fn check_manifest(path: &Path, manifest: &Manifest) -> Result<()> {
    let afresh = "run without --resume to start afresh";
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot resume: reading {}", path.display()))?;
    let stored: ManifestFile = match serde_json::from_str(&text) {
        Ok(m) => m,
        Err(e) => bail!(
            "cannot resume: {}: unreadable ({e}); {afresh}",
            path.display()
        ),
    };
    if stored.format != FORMAT {
        bail!(
            "cannot resume: {} is of format {:?}, this sndt writes {FORMAT:?}; {afresh}",
            path.display(),
            stored.format
        );
    }
    let differences = differences(&stored.options, manifest);
    if !differences.is_empty() {
        bail!(
            "cannot resume: the results in {} were made with different options: {}; {afresh}",
            path.display(),
            differences.join("; ")
        );
    }
    Ok(())
}

/// `option: stored X, now Y` for each option whose value differs.
fn differences(stored: &Manifest, now: &Manifest) -> Vec<String> {
    let none = String::from("(none)");
    let mut keys: Vec<&String> = stored.keys().chain(now.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter()
        .filter_map(|k| {
            let (a, b) = (stored.get(k).unwrap_or(&none), now.get(k).unwrap_or(&none));
            (a != b).then(|| format!("{k}: stored {a}, now {b}"))
        })
        .collect()
}

/// A test hook: `SNDT_EXPERIMENT_STOP_AFTER=N` makes the process exit with
/// [`STOP_EXIT_CODE`] right after its N-th result is stored, so that a test can interrupt
/// an experiment at a known point and resume it.
fn stop_after() -> Option<usize> {
    std::env::var("SNDT_EXPERIMENT_STOP_AFTER")
        .ok()?
        .parse()
        .ok()
}

/// `text` made safe as part of a file name: ASCII letters, digits, `.`, `_` and `-` kept,
/// every other byte written `%XX`, so that different names stay different.
///
/// ```
/// use sndt_host::eval::experiment::store::file_name_part;
/// assert_eq!(file_name_part("synth_00/cam_00"), "synth_00%2Fcam_00");
/// assert_ne!(file_name_part("a/b"), file_name_part("a%2Fb"));
/// ```
pub fn file_name_part(text: &str) -> String {
    let mut out = String::new();
    for b in text.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'.' | b'_' | b'-') {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_name_each_option_that_changed() {
        let m = |pairs: &[(&str, &str)]| -> Manifest {
            pairs
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect()
        };
        let stored = m(&[("--cell", "0.1"), ("--every", "5"), ("dataset", "x")]);
        let now = m(&[("--cell", "0.2"), ("--every", "5"), ("--labels", "gt")]);
        assert_eq!(
            differences(&stored, &now),
            [
                "--cell: stored 0.1, now 0.2",
                "--labels: stored (none), now gt",
                "dataset: stored x, now (none)"
            ]
        );
        assert!(differences(&stored, &stored).is_empty());
    }
}
