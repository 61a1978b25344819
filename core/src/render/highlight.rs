//! How highlighted parts (selection feedback) are shown: tinted towards the highlight colour,
//! or outlined by a band in that colour around them, their own colours kept. The outline
//! style's surfaces record per pixel the nearest surface's depth and whether it is highlighted
//! (the outline keys, plane 0 of the pixel keys, `super::pixel_keys`); after the rendering
//! `shaders/outline.frag` draws the band where a pixel not highlighted lies near one that is.

/// How highlighted parts are drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HighlightStyle {
    /// Their colour mixed towards the highlight colour (the default).
    #[default]
    Tint,
    /// Their own colours, with a band in the highlight colour around them. Needs the
    /// device's `fragmentStoresAndAtomics`.
    Outline,
}

impl HighlightStyle {
    /// Every style.
    pub const ALL: [HighlightStyle; 2] = [HighlightStyle::Tint, HighlightStyle::Outline];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            HighlightStyle::Tint => "tint",
            HighlightStyle::Outline => "outline",
        }
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }
}

#[cfg(test)]
mod tests {
    use super::HighlightStyle;

    #[test]
    fn styles_parse_by_name() {
        for style in HighlightStyle::ALL {
            assert_eq!(HighlightStyle::parse(style.name()), Some(style));
        }
        assert_eq!(HighlightStyle::parse("glow"), None);
        assert_eq!(HighlightStyle::default(), HighlightStyle::Tint);
    }
}
