//! Several standard views of one scene side by side in one picture.

use crate::camera::{Camera, View};
use crate::colour::srgba_to_bytes;
use crate::error::RenderError;
use crate::offscreen::Renderer;
use crate::picture::Image;
use crate::scene::Scene;

/// Layout of a contact sheet.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSheet {
    /// Views, left to right.
    pub views: Vec<View>,
    /// Size of each view's tile in pixels.
    pub tile_size: [u32; 2],
    /// Pixels of background between and around the tiles.
    pub gap: u32,
    /// Writes each view's name in a strip above its tile, and under it
    /// which way the mother's body lies in the picture ([`View::orientation`]).
    pub labels: bool,
}

impl Default for ContactSheet {
    /// Anterior, lateral and inferior views, 512 x 512 each, labelled.
    fn default() -> Self {
        Self {
            views: View::THREE.to_vec(),
            tile_size: [512, 512],
            gap: 8,
            labels: true,
        }
    }
}

/// Pixels per font pixel of the labels (the font is 8 x 8).
const LABEL_SCALE: u32 = 2;

/// Height of the strip that holds a label: the name, the orientation in
/// the font at its own size below it, and a little air below each.
pub const LABEL_STRIP: u32 = 8 * LABEL_SCALE + 4 + 8 + 6;

impl Renderer {
    /// Renders `scene` from each view of `sheet` at one common scale
    /// (orthographic, so sizes compare across tiles) into one picture.
    pub fn contact_sheet(
        &mut self,
        scene: &Scene,
        sheet: &ContactSheet,
    ) -> Result<Image, RenderError> {
        let bounds = scene.bounds()?;
        let [tile_w, tile_h] = sheet.tile_size;
        let count = sheet.views.len() as u32;
        if count == 0 {
            return Err(RenderError::InvalidCamera(
                "a contact sheet needs at least one view".into(),
            ));
        }
        let mut cameras: Vec<Camera> = sheet
            .views
            .iter()
            .map(|v| Camera::standard(*v, &bounds))
            .collect();
        // One scale for every tile: each keeps the largest extent of any view.
        let common = cameras.iter().fold([0.0_f32; 2], |acc, c| {
            [acc[0].max(c.half_extent[0]), acc[1].max(c.half_extent[1])]
        });
        for camera in &mut cameras {
            camera.half_extent = common;
        }

        let background = srgba_to_bytes(scene.background);
        let strip = if sheet.labels { LABEL_STRIP } else { 0 };
        let width = count * tile_w + (count + 1) * sheet.gap;
        let height = tile_h + strip + 2 * sheet.gap;
        let mut picture = Image::filled(width, height, background);
        let uploaded = self.upload(scene)?;
        for (i, (view, camera)) in sheet.views.iter().zip(&cameras).enumerate() {
            let tile = self.render_uploaded(&uploaded, camera, tile_w, tile_h)?;
            let x = sheet.gap + i as u32 * (tile_w + sheet.gap);
            picture.paste(&tile, x, sheet.gap + strip);
            if sheet.labels {
                let ink = label_ink(scene.background);
                draw_label(&mut picture, &view.name().to_uppercase(), x, sheet.gap, ink, LABEL_SCALE);
                let orientation = in_width(view.orientation(), (tile_w / 8) as usize);
                draw_label(&mut picture, orientation, x, sheet.gap + 8 * LABEL_SCALE + 4, ink, 1);
            }
        }
        Ok(picture)
    }
}

/// The whole clauses of `text` that fit in `chars` characters: a narrow
/// tile keeps "from below: front up", not "... her left to the", whose
/// last words no longer say which way; the viewpoint before the colon
/// ("from her front right, above") is whole or not shown.
fn in_width(text: &str, chars: usize) -> &str {
    if text.len() <= chars {
        return text;
    }
    let viewpoint = text.find(':').unwrap_or(text.len());
    text[..=chars].rfind([',', ':']).filter(|&end| end >= viewpoint).map_or("", |end| &text[..end])
}

/// Dark text on a light background, light text on a dark one.
fn label_ink(background: [f32; 4]) -> [u8; 4] {
    // Rec. 709 luma of the sRGB channels is close enough to pick a contrast.
    let luma = 0.2126 * background[0] + 0.7152 * background[1] + 0.0722 * background[2];
    if luma > 0.5 {
        [40, 40, 40, 255]
    } else {
        [230, 230, 230, 255]
    }
}

/// Writes ASCII text with the public-domain 8x8 font, `scale` times its size.
fn draw_label(picture: &mut Image, text: &str, x: u32, y: u32, ink: [u8; 4], scale: u32) {
    let advance = 8 * scale;
    for (i, c) in text.chars().enumerate() {
        let Some(glyph) = font8x8::legacy::BASIC_LEGACY.get(c as usize) else {
            continue;
        };
        let left = x + i as u32 * advance;
        for (row, bits) in glyph.iter().enumerate() {
            for column in 0..8 {
                // Bit 0 is the leftmost pixel of the row.
                if bits & (1 << column) != 0 {
                    for dy in 0..scale {
                        for dx in 0..scale {
                            picture.set_pixel(
                                left + column * scale + dx,
                                y + row as u32 * scale + dy,
                                ink,
                            );
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_ink_contrasts_with_the_background() {
        assert_eq!(label_ink([1.0, 1.0, 1.0, 1.0]), [40, 40, 40, 255]);
        assert_eq!(label_ink([0.0, 0.0, 0.1, 1.0]), [230, 230, 230, 255]);
    }

    #[test]
    fn a_narrow_tile_keeps_whole_clauses() {
        let text = "from below: front up, her left to the right";
        assert_eq!(in_width(text, 48), text);
        assert_eq!(in_width(text, 32), "from below: front up");
        assert_eq!(in_width(text, 20), "from below: front up");
        assert_eq!(in_width(text, 19), "from below");
        let oblique = "from her front right, above: cranial up";
        assert_eq!(in_width(oblique, 30), "from her front right, above");
        assert_eq!(in_width(oblique, 26), "");
        assert_eq!(in_width(text, 12), "from below");
        assert_eq!(in_width(text, 3), "");
    }

    #[test]
    fn a_label_puts_ink_inside_its_box_only() {
        let mut picture = Image::filled(64, 32, [255; 4]);
        draw_label(&mut picture, "AL", 4, 4, [0, 0, 0, 255], LABEL_SCALE);
        let inked: Vec<(u32, u32)> = (0..32)
            .flat_map(|y| (0..64).map(move |x| (x, y)))
            .filter(|&(x, y)| picture.pixel(x, y) == Some([0, 0, 0, 255]))
            .collect();
        assert!(inked.len() > 20, "{} inked pixels", inked.len());
        assert!(inked
            .iter()
            .all(|&(x, y)| (4..4 + 32).contains(&x) && (4..4 + 16).contains(&y)));
    }
}
