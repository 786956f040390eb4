//! Whole-directory replacement of a command's results: [`StagedDir`].
//!
//! A command writes into a fresh hidden sibling `.<name>.tmp-<pid>` of its result
//! directory `<name>`; [`StagedDir::commit`] then swaps it in (the old directory is
//! renamed to `.<name>.old-<pid>`, the new one into place, the old one deleted). The
//! entries of the old directory that the command does not own (the results of other
//! commands sharing the folder, the user's own files) are moved into the new
//! directory first, so that only this command's earlier files disappear. Until the
//! commit, the old directory is untouched; a [`StagedDir`] dropped unfinished removes
//! its temporary directory, and so does [`remove_uncommitted`] (Ctrl-C).

use std::ffi::{OsStr, OsString};
use std::fs;
use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::OutputError;

/// Temporary directories of unfinished [`StagedDir`]s; also held during a commit, so
/// that an interrupt waits for a commit to end.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Which entries (by file name) of an earlier result directory a command replaces.
pub type Owns = fn(&OsStr) -> bool;

/// A result directory being written; see the module documentation.
#[derive(Debug)]
pub struct StagedDir {
    /// The result directory as the command was given it (for messages).
    target: PathBuf,
    /// The result directory, symbolic links resolved when it exists.
    resolved: PathBuf,
    temp: PathBuf,
    owns: Owns,
    done: bool,
}

/// `.<name>.<what>-<pid>` beside `target`.
fn sibling(parent: &Path, name: &OsStr, what: &str) -> PathBuf {
    let mut s = OsString::from(".");
    s.push(name);
    s.push(format!(".{what}-{}", std::process::id()));
    parent.join(s)
}

/// Whether `name` is a leftover of an interrupted atomic write (`.<file>.<pid>.<n>.tmp`).
fn is_temp_leftover(name: &OsStr) -> bool {
    let n = name.to_string_lossy();
    n.starts_with('.') && n.ends_with(".tmp")
}

impl StagedDir {
    /// Create the temporary directory for results that will replace `target`, with
    /// its parents. Refused before any work: a `target` that exists and is not a
    /// directory, or that is the current directory or one of its parents (`.`).
    /// A symbolic link `target` is followed: the directory it names is replaced.
    /// Temporary directories of the same target left by processes that no longer
    /// run (killed) are removed.
    pub fn create(target: &Path, owns: Owns) -> Result<StagedDir, OutputError> {
        let resolved = match fs::symlink_metadata(target) {
            Ok(_) => {
                let real = fs::canonicalize(target).map_err(|e| OutputError::io(target, e))?;
                if !real.is_dir() {
                    return Err(OutputError::invalid(target, "exists and is not a directory; results go into a directory"));
                }
                let cwd = std::env::current_dir().map_err(|e| OutputError::io(Path::new("."), e))?;
                if real.file_name().is_none() || cwd.starts_with(&real) {
                    return Err(OutputError::invalid(
                        target,
                        "results replace their directory as a whole, so it cannot be the current directory or one of its parents; give a sub-directory",
                    ));
                }
                real
            }
            Err(_) => target.to_path_buf(),
        };
        let name = resolved.file_name().ok_or_else(|| OutputError::invalid(target, "has no final directory name"))?.to_os_string();
        let parent = match resolved.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let temp = sibling(&parent, &name, "tmp");
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        // `create_dir` first: a parent that is a file then fails with "Not a directory".
        if let Err(e) = fs::create_dir(&temp) {
            match e.kind() {
                io::ErrorKind::NotFound => {
                    fs::create_dir_all(&parent).map_err(|e| OutputError::io(target, e))?;
                    fs::create_dir(&temp).map_err(|e| OutputError::io(target, e))?;
                }
                // Left by a killed process that had our pid.
                io::ErrorKind::AlreadyExists => {
                    fs::remove_dir_all(&temp).map_err(|e| OutputError::io(&temp, e))?;
                    fs::create_dir(&temp).map_err(|e| OutputError::io(target, e))?;
                }
                _ => return Err(OutputError::io(target, e)),
            }
        }
        live.push(temp.clone());
        drop(live);
        remove_dead_temps(&parent, &name);
        Ok(StagedDir { target: target.to_path_buf(), resolved, temp, owns, done: false })
    }

    /// Where the results are written until [`StagedDir::commit`].
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The result directory the commit replaces, as given to [`StagedDir::create`].
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Swap the written directory in (module documentation). On failure the earlier
    /// directory is restored as it was and the temporary one removed.
    pub fn commit(self) -> Result<(), OutputError> {
        self.commit_with(|from, to| fs::rename(from, to))
    }

    /// [`StagedDir::commit`] with the renaming function given (failures injected in tests).
    fn commit_with(mut self, rename: impl Fn(&Path, &Path) -> io::Result<()>) -> Result<(), OutputError> {
        let live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        let result = self.swap(&rename);
        if result.is_ok() {
            self.done = true;
        }
        drop(live);
        self.forget();
        result
    }

    /// Carry the foreign entries over, rename the old directory aside and the new one
    /// into place, delete the old one; undo what was done when a step fails. An undo
    /// that fails too is reported, and the temporary directory is then kept (it may
    /// hold foreign entries).
    fn swap(&mut self, rename: &impl Fn(&Path, &Path) -> io::Result<()>) -> Result<(), OutputError> {
        let Ok(meta) = fs::symlink_metadata(&self.resolved) else {
            return rename(&self.temp, &self.resolved).map_err(|e| OutputError::io(&self.resolved, e));
        };
        if !meta.is_dir() {
            return Err(OutputError::invalid(&self.resolved, "exists and is not a directory; results go into a directory"));
        }
        let (target, temp) = (self.resolved.clone(), self.temp.clone());
        let io = |e| OutputError::io(&target, e);
        let mut carried = Vec::new();
        let failed = |e: io::Error, path: &Path, carried: &[OsString], kept: &mut bool| {
            let stuck = carried.iter().filter(|n| rename(&temp.join(n), &target.join(n)).is_err()).count();
            if stuck == 0 {
                return OutputError::io(path, e);
            }
            *kept = true;
            OutputError::io(path, io::Error::new(e.kind(), format!("{e}; {stuck} entries could not be moved back from {}", temp.display())))
        };
        let mut kept = false;
        for entry in fs::read_dir(&target).map_err(io)? {
            let name = entry.map_err(io)?.file_name();
            if (self.owns)(&name) || is_temp_leftover(&name) || temp.join(&name).exists() {
                continue;
            }
            if let Err(e) = rename(&target.join(&name), &temp.join(&name)) {
                let err = failed(e, &target.join(&name), &carried, &mut kept);
                self.done = kept;
                return Err(err);
            }
            carried.push(name);
        }
        let name = target.file_name().expect("checked at creation");
        let old = sibling(temp.parent().expect("a sibling"), name, "old");
        if let Err(e) = rename(&target, &old) {
            let err = failed(e, &target, &carried, &mut kept);
            self.done = kept;
            return Err(err);
        }
        if let Err(e) = rename(&temp, &target) {
            if let Err(back) = rename(&old, &target) {
                self.done = true;
                return Err(OutputError::io(
                    &target,
                    io::Error::new(e.kind(), format!("{e}; the earlier results are in {} ({back})", old.display())),
                ));
            }
            let err = failed(e, &target, &carried, &mut kept);
            self.done = kept;
            return Err(err);
        }
        // The results are in place; a failure to delete the old ones leaves a hidden folder.
        let _ = fs::remove_dir_all(&old);
        #[cfg(unix)]
        if let Ok(d) = fs::File::open(temp.parent().expect("a sibling")) {
            let _ = d.sync_all();
        }
        Ok(())
    }

    /// Remove the temporary directory (unless committed or kept) and stop tracking it.
    fn forget(&mut self) {
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        live.retain(|p| p != &self.temp);
        if !self.done {
            let _ = fs::remove_dir_all(&self.temp);
        }
        self.done = true;
    }
}

impl Drop for StagedDir {
    /// An unfinished result directory (a failure, an interrupt) is removed.
    fn drop(&mut self) {
        if !self.done {
            self.forget();
        }
    }
}

/// Remove the temporary directories of every unfinished [`StagedDir`], right before
/// the process exits (an interrupt outside a time loop); waits for a commit under
/// way, and no new [`StagedDir`] can start afterwards (the process is expected to end).
pub fn remove_uncommitted() {
    let live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    for p in live.iter() {
        let _ = fs::remove_dir_all(p);
    }
    std::mem::forget(live);
}

/// Remove `.<name>.tmp-<pid>` directories in `parent` whose process no longer runs.
fn remove_dead_temps(parent: &Path, name: &OsStr) {
    #[cfg(unix)]
    {
        let mut prefix = OsString::from(".");
        prefix.push(name);
        prefix.push(".tmp-");
        let prefix = prefix.to_string_lossy().into_owned();
        let Ok(entries) = fs::read_dir(parent) else { return };
        for e in entries.flatten() {
            let file = e.file_name();
            let Some(pid) = file.to_str().and_then(|f| f.strip_prefix(prefix.as_str())).and_then(|p| p.parse::<libc::pid_t>().ok()) else {
                continue;
            };
            // SAFETY: signal 0 sends nothing; it only checks whether the process exists.
            let gone = pid > 0 && unsafe { libc::kill(pid, 0) } != 0 && io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH);
            if gone {
                let _ = fs::remove_dir_all(e.path());
            }
        }
    }
    #[cfg(not(unix))]
    let _ = (parent, name);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    fn owns_a(name: &OsStr) -> bool {
        name == "a.txt" || name == "sub"
    }

    /// Names in `dir`, sorted.
    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    /// `root/res` with `a.txt` ("old"), `sub/x` (owned) and `keep.txt` (foreign).
    fn earlier(root: &Path) -> PathBuf {
        let res = root.join("res");
        fs::create_dir_all(res.join("sub")).unwrap();
        fs::write(res.join("a.txt"), "old").unwrap();
        fs::write(res.join("sub/x"), "old").unwrap();
        fs::write(res.join("keep.txt"), "mine").unwrap();
        res
    }

    #[test]
    fn commit_replaces_owned_entries_and_keeps_foreign_ones() {
        let tmp = tempfile::tempdir().unwrap();
        let res = earlier(tmp.path());
        let staged = StagedDir::create(&res, owns_a).unwrap();
        assert!(staged.path().starts_with(tmp.path()) && staged.path() != res);
        fs::write(staged.path().join("a.txt"), "new").unwrap();
        staged.commit().unwrap();
        assert_eq!(names(&res), ["a.txt", "keep.txt"]);
        assert_eq!(fs::read_to_string(res.join("a.txt")).unwrap(), "new");
        assert_eq!(fs::read_to_string(res.join("keep.txt")).unwrap(), "mine");
        assert_eq!(names(tmp.path()), ["res"]);
    }

    #[test]
    fn commit_into_a_new_directory_creates_its_parents() {
        let tmp = tempfile::tempdir().unwrap();
        let res = tmp.path().join("p/q/res");
        let staged = StagedDir::create(&res, owns_a).unwrap();
        fs::write(staged.path().join("a.txt"), "new").unwrap();
        staged.commit().unwrap();
        assert_eq!(names(&res), ["a.txt"]);
        assert_eq!(names(&tmp.path().join("p/q")), ["res"]);
    }

    #[test]
    fn a_failed_last_write_leaves_the_earlier_directory_and_no_temp() {
        let tmp = tempfile::tempdir().unwrap();
        let res = earlier(tmp.path());
        let write_all = |dir: &Path| -> Result<(), OutputError> {
            super::super::write_atomic(&dir.join("a.txt"), b"new")?;
            // The last file fails (e.g. disk full).
            Err(OutputError::io(&dir.join("summary.json"), io::Error::other("simulated")))
        };
        let staged = StagedDir::create(&res, owns_a).unwrap();
        assert!(write_all(staged.path()).is_err());
        drop(staged);
        assert_eq!(names(tmp.path()), ["res"]);
        assert_eq!(names(&res), ["a.txt", "keep.txt", "sub"]);
        assert_eq!(fs::read_to_string(res.join("a.txt")).unwrap(), "old");
    }

    #[test]
    fn a_failed_rename_at_any_step_of_the_commit_restores_the_earlier_directory() {
        // Renames: keep.txt carried over (1), res aside (2), temp into place (3).
        for failing in 1..=3 {
            let tmp = tempfile::tempdir().unwrap();
            let res = earlier(tmp.path());
            let staged = StagedDir::create(&res, owns_a).unwrap();
            fs::write(staged.path().join("a.txt"), "new").unwrap();
            let calls = Cell::new(0);
            let err = staged
                .commit_with(|from, to| {
                    calls.set(calls.get() + 1);
                    if calls.get() == failing {
                        return Err(io::Error::other("simulated"));
                    }
                    fs::rename(from, to)
                })
                .unwrap_err();
            assert!(err.to_string().contains("simulated"), "{err}");
            assert_eq!(names(tmp.path()), ["res"], "rename {failing}");
            assert_eq!(names(&res), ["a.txt", "keep.txt", "sub"], "rename {failing}");
            assert_eq!(fs::read_to_string(res.join("a.txt")).unwrap(), "old");
            assert_eq!(fs::read_to_string(res.join("keep.txt")).unwrap(), "mine");
        }
    }

    #[test]
    fn refuses_a_file_and_the_current_directory() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("f");
        fs::write(&file, "x").unwrap();
        let err = StagedDir::create(&file, owns_a).unwrap_err();
        assert!(err.to_string().contains("not a directory"), "{err}");
        let err = StagedDir::create(&file.join("res"), owns_a).unwrap_err();
        assert!(err.to_string().contains("Not a directory") && err.to_string().contains("f/res"), "{err}");
        let err = StagedDir::create(Path::new("."), owns_a).unwrap_err();
        assert!(err.to_string().contains("current directory"), "{err}");
        assert_eq!(names(tmp.path()), ["f"]);
    }

    #[test]
    fn dropped_directories_are_untracked_and_removed() {
        let tmp = tempfile::tempdir().unwrap();
        let staged = StagedDir::create(&tmp.path().join("res"), owns_a).unwrap();
        assert!(staged.path().is_dir());
        let live = LIVE.lock().unwrap();
        assert!(live.contains(&staged.path().to_path_buf()));
        drop(live);
        drop(staged);
        assert!(LIVE.lock().unwrap().iter().all(|p| !p.starts_with(tmp.path())));
        assert_eq!(names(tmp.path()), Vec::<String>::new());
    }
}
