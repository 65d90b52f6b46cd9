//! Colour spaces and the colour maps of scalar fields.
//!
//! Colours given by callers are sRGB (as in CSS or a paint program); the
//! shader lights in linear light and the sRGB target encodes the result
//! back, so shading gradients are perceptually even.

/// sRGB-encoded channel (0..=1) to linear light (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear-light channel (0..=1) to sRGB encoding (IEC 61966-2-1).
pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// An sRGB colour with straight alpha, converted to linear RGB, alpha kept.
pub fn srgba_to_linear(c: [f32; 4]) -> [f32; 4] {
    [
        srgb_to_linear(c[0]),
        srgb_to_linear(c[1]),
        srgb_to_linear(c[2]),
        c[3],
    ]
}

/// sRGB colour (0..=1 channels) to 8-bit RGBA bytes, rounded.
pub fn srgba_to_bytes(c: [f32; 4]) -> [u8; 4] {
    c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// Colour maps for per-vertex scalar fields (stress, stretch).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColourMap {
    /// Perceptually uniform sequential map (matplotlib's viridis): for
    /// magnitudes such as stretch or von Mises stress.
    #[default]
    Viridis,
    /// Diverging blue-white-red map (Moreland 2009, "cool to warm"): for
    /// signed fields centred on zero.
    CoolWarm,
}

impl ColourMap {
    /// Every map, in the order of the rows of the colour-map texture.
    pub const ALL: [ColourMap; 2] = [ColourMap::Viridis, ColourMap::CoolWarm];

    /// Texels per map in the lookup table.
    pub const RESOLUTION: usize = 256;

    /// Row of this map in the lookup texture.
    pub fn row(self) -> usize {
        self as usize
    }

    /// Nine sRGB control points at t = 0, 1/8, ..., 1.
    fn control_points(self) -> [[u8; 3]; 9] {
        match self {
            // matplotlib viridis sampled at eighths of its range.
            ColourMap::Viridis => [
                [68, 1, 84],
                [71, 45, 123],
                [59, 82, 139],
                [44, 114, 142],
                [33, 145, 140],
                [40, 174, 128],
                [94, 201, 98],
                [173, 220, 48],
                [253, 231, 37],
            ],
            // K. Moreland, "Diverging Color Maps for Scientific Visualization", ISVC 2009.
            ColourMap::CoolWarm => [
                [59, 76, 192],
                [98, 130, 234],
                [141, 176, 254],
                [184, 208, 249],
                [221, 221, 221],
                [245, 196, 173],
                [244, 154, 123],
                [222, 96, 77],
                [180, 4, 38],
            ],
        }
    }

    /// sRGB colour of the map at `t` in 0..=1 (clamped), as 8-bit RGBA.
    pub fn sample(self, t: f32) -> [u8; 4] {
        let points = self.control_points();
        let x = t.clamp(0.0, 1.0) * (points.len() - 1) as f32;
        let i = (x.floor() as usize).min(points.len() - 2);
        let f = x - i as f32;
        let (a, b) = (points[i], points[i + 1]);
        let mix = |k: usize| (a[k] as f32 + (b[k] as f32 - a[k] as f32) * f).round() as u8;
        [mix(0), mix(1), mix(2), 255]
    }

    /// The lookup table of every map: `ALL.len()` rows of `RESOLUTION`
    /// sRGB RGBA8 texels, ready to upload as an sRGB texture.
    pub fn lookup_table() -> Vec<u8> {
        let mut texels = Vec::with_capacity(Self::ALL.len() * Self::RESOLUTION * 4);
        for map in Self::ALL {
            for i in 0..Self::RESOLUTION {
                texels.extend_from_slice(&map.sample(i as f32 / (Self::RESOLUTION - 1) as f32));
            }
        }
        texels
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_is_identity() {
        for i in 0..=255 {
            let c = i as f32 / 255.0;
            assert!(
                (linear_to_srgb(srgb_to_linear(c)) - c).abs() < 1e-5,
                "channel {i}"
            );
        }
    }

    #[test]
    fn srgb_mid_grey_is_about_a_fifth_linear() {
        // sRGB 0.5 is 21.4 % linear light.
        assert!((srgb_to_linear(0.5) - 0.214).abs() < 1e-3);
    }

    #[test]
    fn colour_maps_hit_their_end_points_and_clamp() {
        assert_eq!(ColourMap::Viridis.sample(0.0), [68, 1, 84, 255]);
        assert_eq!(ColourMap::Viridis.sample(1.0), [253, 231, 37, 255]);
        assert_eq!(
            ColourMap::Viridis.sample(-3.0),
            ColourMap::Viridis.sample(0.0)
        );
        assert_eq!(ColourMap::CoolWarm.sample(0.5), [221, 221, 221, 255]);
        assert_eq!(ColourMap::CoolWarm.sample(7.0), [180, 4, 38, 255]);
    }

    #[test]
    fn lookup_table_has_one_row_per_map() {
        let table = ColourMap::lookup_table();
        assert_eq!(
            table.len(),
            ColourMap::ALL.len() * ColourMap::RESOLUTION * 4
        );
        let row = ColourMap::CoolWarm.row() * ColourMap::RESOLUTION * 4;
        assert_eq!(&table[row..row + 4], &[59, 76, 192, 255]);
    }
}
