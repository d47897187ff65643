//! Output folders that never look complete when they are not.
//!
//! A folder of outputs (an animation's frames, an export) is written into a hidden temporary
//! sibling (`.pelage-PID-staged.tmp`) and renamed to its name only once every file is in it. An
//! existing output folder is replaced only when it holds nothing but what this command writes (a
//! previous run's output); any other existing folder is refused before work starts. On an error
//! the temporary folder is removed; an interrupted process leaves at most a hidden `.tmp` folder.
//! An output name that is a symbolic link (to an earlier sweep or export, say) is written
//! through: the folder it leads to is replaced, beside it, and the link stays a link.

use super::Failure;
use std::path::{Path, PathBuf};

/// Which entries an existing output folder may hold for it to be replaced.
pub struct EntryRule {
    /// Whether a top-level entry (file or folder name) is one this command writes.
    pub accepts: Box<dyn Fn(&str) -> bool>,
    /// What an accepted entry is, for the refusal message ("a frame of a previous render").
    pub what: &'static str,
}

/// An output folder being written: files go to [`StagedFolder::path`], renamed to the target at
/// [`StagedFolder::commit`]; dropped without a commit, it removes itself.
pub struct StagedFolder {
    /// The output as the user named it (for messages).
    target: PathBuf,
    /// The folder actually replaced: `target`, or where a symbolic link named `target` leads.
    resolved: PathBuf,
    temporary: PathBuf,
    rule: EntryRule,
    committed: bool,
}

impl StagedFolder {
    /// Checks the target can be (re)placed and creates the temporary folder beside it.
    pub fn create(target: &Path, rule: EntryRule) -> Result<StagedFolder, Failure> {
        let other = |m: String| Failure::other(format!("{}: {m}", target.display()));
        let name = target.file_name().ok_or_else(|| {
            Failure::bad_input(format!("-o {}: not a folder name", target.display()))
        })?;
        if name.len() > pelage::output::MAX_FILE_NAME_BYTES {
            return Err(Failure::bad_input(format!(
                "-o {}: the name is {} bytes, longer than the {} a file system allows",
                target.display(),
                name.len(),
                pelage::output::MAX_FILE_NAME_BYTES
            )));
        }
        let resolved = through_links(target).map_err(|e| {
            Failure::bad_input(format!(
                "-o {}: a link that cannot be followed ({e})",
                target.display()
            ))
        })?;
        if resolved.exists() {
            replaceable(target, &rule)?;
        }
        let parent = parent_of(&resolved);
        std::fs::create_dir_all(parent).map_err(|e| {
            other(format!(
                "cannot create the folder {}: {e}",
                parent.display()
            ))
        })?;
        // A short name whatever the target's length (file systems allow 255 bytes a name).
        let temporary = parent.join(format!(".pelage-{}-staged.tmp", std::process::id()));
        if temporary.exists() {
            let _ = std::fs::remove_dir_all(&temporary);
        }
        std::fs::create_dir(&temporary)
            .map_err(|e| other(format!("cannot create the temporary folder: {e}")))?;
        Ok(StagedFolder {
            target: target.to_path_buf(),
            resolved,
            temporary,
            rule,
            committed: false,
        })
    }

    /// Where the files go until [`StagedFolder::commit`].
    pub fn path(&self) -> &Path {
        &self.temporary
    }

    /// Moves the finished folder into place (replacing a previous run's output).
    pub fn commit(mut self) -> Result<(), Failure> {
        let other = |m: String| Failure::other(format!("{}: {m}", self.target.display()));
        let old = self.temporary.with_extension("old");
        if self.resolved.exists() {
            replaceable(&self.target, &self.rule)?;
            std::fs::rename(&self.resolved, &old)
                .map_err(|e| other(format!("cannot move the previous output aside: {e}")))?;
        }
        std::fs::rename(&self.temporary, &self.resolved)
            .map_err(|e| other(format!("cannot move the output into place: {e}")))?;
        self.committed = true;
        if old.exists() {
            let _ = std::fs::remove_dir_all(&old);
        }
        Ok(())
    }
}

impl Drop for StagedFolder {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_dir_all(&self.temporary);
        }
    }
}

/// Where `path` leads through symbolic links (at most 40, as the kernel allows): `path` itself
/// when it is no link, the link's target (relative targets taken from the link's folder)
/// otherwise; a dangling link gives the path it would create.
fn through_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&current)?;
                current = parent_of(&current).join(target);
            }
            _ => return Ok(current),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

/// An existing output folder may be replaced only when every entry in it is accepted by `rule`.
fn replaceable(target: &Path, rule: &EntryRule) -> Result<(), Failure> {
    let refuse = |why: String| {
        Failure::bad_input(format!(
            "-o {}: {why}; choose a new folder or remove it",
            target.display()
        ))
    };
    if !target.is_dir() {
        return Err(refuse("exists and is not a folder".into()));
    }
    let entries = std::fs::read_dir(target).map_err(|e| refuse(format!("cannot be read ({e})")))?;
    for entry in entries {
        let entry = entry.map_err(|e| refuse(format!("cannot be read ({e})")))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if !(rule.accepts)(&name) {
            return Err(refuse(format!(
                "holds {name:?}, which is not {}",
                rule.what
            )));
        }
    }
    Ok(())
}

/// The folder a path's file goes into (`.` for a bare file name).
pub fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}
