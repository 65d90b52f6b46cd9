//! Picks the pelvis landmarks on the HuBMAP Visible Human Female pelvis
//! (separate bones in the GLB) and prints the landmarks file of the merged
//! STL, as shipped in assets/anatomy. The procedure is
//! `carus_anatomy::import::pick` (docs/IMPORT.md).
//!
//! cargo run --release -p carus-anatomy --example pick_pelvis_landmarks -- \
//!     assets/anatomy/visible-human-female-pelvis.glb > landmarks.toml

use std::path::Path;

use carus_anatomy::import::{pick, read_gltf_parts, visible_human_glb_axes, visible_human_stl_axes, Units};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let glb = std::env::args()
        .nth(1)
        .ok_or("usage: pick_pelvis_landmarks PELVIS.glb")?;
    let glb = Path::new(&glb);
    let parts = read_gltf_parts(glb)?;
    let bones = pick::PelvisBones::from_named_parts(&parts, visible_human_glb_axes().to_anatomical(glb)?, 1.0)?;
    let landmarks = pick::pick_landmarks(&bones)?;
    let file = pick::to_landmarks_file(
        &landmarks,
        Path::new("visible-human-female-pelvis.stl"),
        Units::Millimetres,
        visible_human_stl_axes(),
        Some(DESCRIPTION.into()),
    )?;
    print!("{}", toml::to_string(&file)?);
    Ok(())
}

const DESCRIPTION: &str = "Visible Human Female pelvis (HuBMAP 3D Reference Organ for Pelvis, Female v1.2, \
CC BY 4.0, see ATTRIBUTION.md). Landmarks picked on the separate bones of visible-human-female-pelvis.glb \
by carus_anatomy::import::pick (examples/pick_pelvis_landmarks.rs; docs/IMPORT.md), given in the \
coordinates of visible-human-female-pelvis.stl (mm; x to the body's left, y posterior, z cranial).";
