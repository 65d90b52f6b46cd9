//! Writing the files a run or a solve leaves for its user.

use std::io::{self, Write};
use std::path::Path;

/// Writes `bytes` to `path` whole, or leaves no file: one the disk refused
/// part way (a full disk) is removed, so that no half file is taken for a
/// result and its space is freed. A file that could not be opened is left
/// as it was (a read-only earlier result is not deleted).
pub fn write_whole(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut file = std::fs::File::create(path)?;
    file.write_all(bytes).inspect_err(|_| {
        drop(file);
        let _ = std::fs::remove_file(path);
    })
}

/// Writes `bytes` beside `path` (as `NAME.partial`) whole, then renames
/// it over `path`: an interrupted write or a full disk leaves the earlier
/// file as it was, and a reader (the viewer following a run, ParaView)
/// never meets a half-written one.
pub fn replace_whole(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut partial = path.as_os_str().to_owned();
    partial.push(".partial");
    let partial = std::path::PathBuf::from(partial);
    write_whole(&partial, bytes)?;
    std::fs::rename(&partial, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A whole write lands; one that cannot open its file leaves what was
    /// there.
    #[test]
    fn a_file_is_written_whole_or_left_as_it_was() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("result.csv");
        write_whole(&path, b"a,b\n1,2\n").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"a,b\n1,2\n");
        // A folder where the file goes: refused, and the folder kept.
        let blocked = dir.path().join("blocked");
        std::fs::create_dir(&blocked).unwrap();
        assert!(write_whole(&blocked, b"x").is_err());
        assert!(blocked.is_dir());
    }
}
