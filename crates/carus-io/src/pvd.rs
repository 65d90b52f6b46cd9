//! ParaView collection (`.pvd`): the list of frames with their simulated
//! times, which ParaView opens as one time series.

use std::path::{Path, PathBuf};

use crate::error::WriteError;
use crate::xml_attr::attribute;

/// Frames of a time series: (simulated time in s, file path relative to
/// the `.pvd`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PvdCollection {
    frames: Vec<(f64, String)>,
}

impl PvdCollection {
    /// An empty collection.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the frame at `time_s`, stored at `relative_path` (forward
    /// slashes, relative to the `.pvd` file).
    pub fn push(&mut self, time_s: f64, relative_path: impl Into<String>) {
        self.frames.push((time_s, relative_path.into()));
    }

    /// The frames so far.
    pub fn frames(&self) -> &[(f64, String)] {
        &self.frames
    }

    /// The collection as XML text.
    pub fn to_xml(&self) -> String {
        let mut xml = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (time_s, file) in &self.frames {
            xml.push_str(&format!(
                "    <DataSet timestep=\"{time_s:e}\" group=\"\" part=\"0\" file=\"{}\"/>\n",
                escape(file)
            ));
        }
        xml.push_str("  </Collection>\n</VTKFile>\n");
        xml
    }

    /// Writes the collection to `path` (rewritten whole, so a run cut off
    /// after any frame still leaves a valid series).
    pub fn write(&self, path: &Path) -> Result<(), WriteError> {
        let io_error = |cause| WriteError::Io {
            path: PathBuf::from(path),
            cause,
        };
        // A full disk leaves the earlier list, whose frames ParaView still
        // opens, not a cut one.
        crate::output::replace_whole(path, self.to_xml().as_bytes()).map_err(io_error)
    }

    /// Reads the frames of a `.pvd` written by [`PvdCollection::write`] (or
    /// any flat ParaView collection).
    pub fn parse(xml: &str) -> Option<PvdCollection> {
        let mut collection = PvdCollection::new();
        for tag in xml.split("<DataSet").skip(1) {
            let tag = &tag[..tag.find('>')?];
            let time_s: f64 = attribute(tag, "timestep")?.parse().ok()?;
            collection.push(time_s, unescape(&attribute(tag, "file")?));
        }
        Some(collection)
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn unescape(text: &str) -> String {
    text.replace("&quot;", "\"")
        .replace("&gt;", ">")
        .replace("&lt;", "<")
        .replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collections_round_trip_with_exact_times_and_escaped_names() {
        let mut pvd = PvdCollection::new();
        pvd.push(0.0, "frames/frame_00000.vtu");
        pvd.push(0.1 + 0.2, "frames/a&b \"q\".vtu");
        pvd.push(1e-9, "frames/frame_00002.vtu");
        let xml = pvd.to_xml();
        assert!(xml.contains("type=\"Collection\""));
        assert!(xml.contains("a&amp;b &quot;q&quot;.vtu"));
        assert_eq!(PvdCollection::parse(&xml).unwrap(), pvd);
    }

    /// A collection saved by another writer: single quotes, attributes on
    /// their own lines, a name ending in `file`.
    #[test]
    fn collections_from_other_writers_are_read() {
        let xml = "<VTKFile type='Collection'><Collection>\n<DataSet timestep='0.5'\n\tprofile='x' file='a.vtu'/>\n</Collection></VTKFile>";
        let pvd = PvdCollection::parse(xml).unwrap();
        assert_eq!(pvd.frames(), [(0.5, "a.vtu".to_string())]);
    }
}
