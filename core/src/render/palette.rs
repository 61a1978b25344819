//! The colours cadr draws with besides the materials' and the background's: the edge lines
//! (feature edges, silhouettes, wireframe; dashed hidden lines a lighter shade of them) and
//! the highlight (what highlighted parts are tinted towards, or outlined in), with the width
//! of the outline band. They reach the shaders through the frame uniforms, so a replayed frame
//! follows a change too.

/// Display RGB values in 0..1 (what a PNG stores).
pub type DisplayRgb = [f32; 3];

/// The colours of edge lines and highlights, and the outline band's width.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Palette {
    /// Edge lines and silhouettes.
    pub edges: DisplayRgb,
    /// Highlighted parts: the tint's target colour, the outline band's colour.
    pub highlight: DisplayRgb,
    /// The outline band's width in pixels, 1 to [`Palette::MAX_OUTLINE_WIDTH`].
    pub outline_width: u32,
}

/// Checks that every channel of `color`, the colour named `what` in the error, is a finite
/// value in 0..1.
pub(crate) fn check_display_rgb(what: &str, color: DisplayRgb) -> Result<(), String> {
    match color.iter().find(|c| !(0.0..=1.0).contains(*c)) {
        Some(value) => Err(format!("{what} colour {color:?}: {value} is not in 0..1")),
        None => Ok(()),
    }
}

impl Palette {
    /// The default: near-black lines, an orange highlight, a band 2 pixels wide.
    pub const DEFAULT: Palette = Palette {
        edges: [0.06, 0.07, 0.09],
        highlight: [1.0, 0.55, 0.05],
        outline_width: 2,
    };

    /// The widest outline band, in pixels (the band's shader searches a square this wide
    /// around every pixel).
    pub const MAX_OUTLINE_WIDTH: u32 = 8;

    /// Checks that every channel is a finite value in 0..1 and the width is 1 to
    /// [`Palette::MAX_OUTLINE_WIDTH`].
    pub fn validate(&self) -> Result<(), String> {
        check_display_rgb("edge", self.edges)?;
        check_display_rgb("highlight", self.highlight)?;
        if !(1..=Self::MAX_OUTLINE_WIDTH).contains(&self.outline_width) {
            return Err(format!(
                "outline width {} pixels: expected 1 to {}",
                self.outline_width,
                Self::MAX_OUTLINE_WIDTH
            ));
        }
        Ok(())
    }
}

impl Default for Palette {
    fn default() -> Self {
        Palette::DEFAULT
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
mod tests {
    use super::*;

    #[test]
    fn colours_outside_0_to_1_and_widths_outside_1_to_8_are_refused() {
        assert_eq!(Palette::DEFAULT.validate(), Ok(()));
        let dark_highlight = Palette {
            highlight: [0.0, f32::NAN, 0.0],
            ..Palette::DEFAULT
        };
        let error = dark_highlight.validate().unwrap_err();
        assert!(error.starts_with("highlight colour"), "{error}");
        let bright_edges = Palette {
            edges: [1.5, 0.0, 0.0],
            ..Palette::DEFAULT
        };
        assert!(bright_edges
            .validate()
            .unwrap_err()
            .contains("1.5 is not in 0..1"));
        for width in [0, 9] {
            let band = Palette {
                outline_width: width,
                ..Palette::DEFAULT
            };
            assert!(band.validate().unwrap_err().contains("expected 1 to 8"));
        }
    }
}
