//! Writing a file so that a crash, a kill or a full disk never leaves a half-written file in
//! place of the previous one: the content goes into a unique temporary file beside the
//! target, is flushed to disk (`fsync`), and only then renamed over the target (an atomic
//! step on POSIX file systems); the directory is synced so the rename itself survives a
//! power cut. Every file sndt writes goes through [`write_atomic`].

use anyhow::{Context, Result};
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A unique temporary path beside `path` (hidden, with the process id and a counter, so
/// concurrent writers never share one); its directory is created.
pub fn temporary(path: &Path) -> Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let parent = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    let name = path
        .file_name()
        .with_context(|| format!("{}: not a file name", path.display()))?;
    Ok(parent.join(format!(
        ".{}.tmp-{}-{}",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )))
}

/// Writes `path` atomically: `write` fills a temporary file (given by its path, for
/// encoders that open files themselves), which is synced and renamed over `path`. On an
/// error the temporary file is removed and `path` is untouched.
///
/// ```
/// use sndt_host::atomic::write_atomic;
/// let path = std::env::temp_dir().join(format!("sndt-atomic-{}.txt", std::process::id()));
/// write_atomic(&path, |tmp| Ok(std::fs::write(tmp, "one")?)).unwrap();
/// assert!(write_atomic(&path, |_| anyhow::bail!("disk full")).is_err());
/// assert_eq!(std::fs::read_to_string(&path).unwrap(), "one"); // the old content stays
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temporary(path)?;
    let result = write(&tmp).and_then(|()| commit(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Makes a finished temporary file `tmp` (from [`temporary`]) the file `path`: syncs it,
/// renames it over `path`, syncs the directory.
pub fn commit(tmp: &Path, path: &Path) -> Result<()> {
    File::open(tmp)
        .and_then(|f| f.sync_all())
        .with_context(|| format!("syncing {}", tmp.display()))?;
    std::fs::rename(tmp, path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    if let Some(dir) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        // Not every platform can sync a directory; the rename has happened either way.
        let _ = File::open(dir).and_then(|d| d.sync_all());
    }
    Ok(())
}

/// [`write_atomic`] of a byte string.
///
/// ```
/// let path = std::env::temp_dir().join(format!("sndt-atomic-bytes-{}", std::process::id()));
/// sndt_host::atomic::write_bytes(&path, b"map").unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"map");
/// # std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_bytes(path: &Path, bytes: impl AsRef<[u8]>) -> Result<()> {
    let bytes = bytes.as_ref();
    write_atomic(path, |tmp| {
        let mut f = File::create(tmp).with_context(|| format!("creating {}", path.display()))?;
        let (first, rest) = bytes.split_at(bytes.len() / 2);
        f.write_all(first)
            .with_context(|| format!("writing {}", path.display()))?;
        if let Some(ms) = write_pause_ms() {
            f.flush()?;
            std::thread::sleep(std::time::Duration::from_millis(ms));
        }
        f.write_all(rest)
            .with_context(|| format!("writing {}", path.display()))
    })
}

/// A test hook: `SNDT_WRITE_PAUSE_MS` makes [`write_bytes`] pause halfway through its
/// content, so a test can kill the process while a file is half written (and check that
/// the previous file is still whole).
fn write_pause_ms() -> Option<u64> {
    std::env::var("SNDT_WRITE_PAUSE_MS").ok()?.parse().ok()
}
