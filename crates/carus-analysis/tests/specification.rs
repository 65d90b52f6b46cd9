//! The specification shipped in docs/spec is the one the project is built
//! to: each file present under its title, and the same text as the
//! workplace's shared docs wherever those sit beside the clone.

use std::path::Path;

const FILES: [(&str, &str); 5] = [
    ("CARDINAL_MOVEMENTS.md", "# Cardinal movements"),
    ("CONVENTIONS.md", "# Conventions"),
    ("REFERENCE_DATA.md", "# Reference data"),
    ("VALIDATION.md", "# Validation cases"),
    ("DESIGN.md", "# Design"),
];

#[test]
fn the_shipped_specification_is_the_shared_one() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    for (file, title) in FILES {
        let shipped = std::fs::read_to_string(root.join("docs/spec").join(file))
            .unwrap_or_else(|e| panic!("docs/spec/{file}: {e}"));
        assert!(shipped.starts_with(title), "docs/spec/{file} starts {:?}", shipped.lines().next());
        let shared = root.join("../shared/docs").join(file);
        if shared.exists() {
            assert_eq!(shipped, std::fs::read_to_string(&shared).unwrap(), "docs/spec/{file} differs from {}: copy it again", shared.display());
        }
    }
}
