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
