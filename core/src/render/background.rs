//! The picture's background: a vertical gradient (one colour when both ends agree), drawn
//! under what a frame drew after its rendering, so every display mode and transparency method
//! meets the same background.

use super::palette::check_display_rgb;

/// The background's colours, as display RGB values in 0..1 (what a PNG stores).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Background {
    /// The colour of the picture's top row.
    pub top: [f32; 3],
    /// The colour of its bottom row; rows between blend linearly.
    pub bottom: [f32; 3],
}

impl Background {
    /// The default: a light sky-grey at the top to a deeper blue-grey at the bottom, as CAD
    /// tools show, which sets light and dark parts apart from it.
    pub const GRADIENT: Background = Background {
        top: [0.93, 0.95, 0.97],
        bottom: [0.64, 0.69, 0.76],
    };

    /// One colour everywhere.
    pub const fn flat(color: [f32; 3]) -> Background {
        Background {
            top: color,
            bottom: color,
        }
    }

    /// The colour at the centre of pixel row `y` of a picture `height` rows high, as the
    /// background shader computes it.
    pub fn color_at(&self, y: u32, height: u32) -> [f32; 3] {
        let down = (y as f32 + 0.5) / height.max(1) as f32;
        std::array::from_fn(|i| self.top[i] + (self.bottom[i] - self.top[i]) * down)
    }

    /// [`Background::color_at`] as 8-bit values.
    pub fn rgb8_at(&self, y: u32, height: u32) -> [u8; 3] {
        self.color_at(y, height)
            .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
    }

    /// Checks that every channel is a finite value in 0..1.
    pub fn validate(&self) -> Result<(), String> {
        check_display_rgb("background top", self.top)?;
        check_display_rgb("background bottom", self.bottom)
    }
}

impl Default for Background {
    fn default() -> Self {
        Background::GRADIENT
    }
}

#[cfg(test)]
mod tests {
    use super::Background;

    #[test]
    fn rows_blend_from_top_to_bottom() {
        let background = Background::GRADIENT;
        let first = background.color_at(0, 100);
        let last = background.color_at(99, 100);
        for i in 0..3 {
            assert!((first[i] - background.top[i]).abs() < 0.005);
            assert!((last[i] - background.bottom[i]).abs() < 0.005);
        }
        assert_eq!(Background::flat([0.5; 3]).rgb8_at(7, 10), [128; 3]);
        assert!(Background::flat([1.5, 0.0, 0.0]).validate().is_err());
        assert!(Background::flat([f32::NAN, 0.0, 0.0]).validate().is_err());
        assert!(Background::GRADIENT.validate().is_ok());
    }
}
