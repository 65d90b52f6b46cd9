//! Reading the files a user names. A regular file is read whole (its size
//! bounds the read); a pipe or device has no size, so it is read up to
//! [`STREAM_LIMIT_BYTES`] and refused past it: `/dev/zero` given as a
//! mesh would otherwise fill the memory before any error could be said.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

/// The most read from a file that is not a regular file (a pipe, a
/// device): far above any scenario or mesh piped in.
pub const STREAM_LIMIT_BYTES: u64 = 256 << 20;

/// The bytes of `path`, as `std::fs::read` gives them, but bounded.
pub fn read_bytes(path: &Path) -> io::Result<Vec<u8>> {
    read_within(path, STREAM_LIMIT_BYTES)
}

fn read_within(path: &Path, stream_limit_bytes: u64) -> io::Result<Vec<u8>> {
    let file = File::open(path)?;
    let metadata = file.metadata()?;
    if metadata.is_file() {
        let mut bytes = Vec::with_capacity(metadata.len() as usize);
        (&file).read_to_end(&mut bytes)?;
        return Ok(bytes);
    }
    let mut bytes = Vec::new();
    file.take(stream_limit_bytes + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > stream_limit_bytes {
        return Err(io::Error::new(
            io::ErrorKind::FileTooLarge,
            format!(
                "it is not a regular file and did not end within {} MiB; name a file on disk",
                stream_limit_bytes as f64 / (1u64 << 20) as f64
            ),
        ));
    }
    Ok(bytes)
}

/// The text of `path`, as `std::fs::read_to_string` gives it, but bounded.
pub fn read_text(path: &Path) -> io::Result<String> {
    String::from_utf8(read_bytes(path)?).map_err(|_| {
        io::Error::new(io::ErrorKind::InvalidData, "stream did not contain valid UTF-8")
    })
}

/// The line, from 1, that byte `offset` of a file's bytes lies on, for
/// messages that name the line at fault.
pub fn line_at(bytes: &[u8], offset: usize) -> usize {
    bytes[..offset.min(bytes.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_regular_file_reads_whole() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.toml");
        std::fs::write(&path, "name = \"x\"\n").unwrap();
        assert_eq!(read_text(&path).unwrap(), "name = \"x\"\n");
        assert_eq!(read_bytes(&path).unwrap(), b"name = \"x\"\n");
    }

    /// An endless device is refused after the limit, not read until the
    /// memory runs out.
    #[cfg(unix)]
    #[test]
    fn an_endless_device_is_refused() {
        let e = read_within(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::FileTooLarge);
        assert!(e.to_string().contains("did not end within 1 MiB"), "{e}");
        assert!(read_bytes(Path::new("/dev/null")).unwrap().is_empty());
    }

    #[test]
    fn text_that_is_not_utf8_is_refused_as_std_does() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.toml");
        std::fs::write(&path, [0xff, 0xfe]).unwrap();
        let ours = read_text(&path).unwrap_err();
        let std = std::fs::read_to_string(&path).unwrap_err();
        assert_eq!((ours.kind(), ours.to_string()), (std.kind(), std.to_string()));
    }
}
