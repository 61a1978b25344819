//! Section planes: up to [`MAX_SECTION_PLANES`] planes in world space, each keeping the
//! half-space `n·p + d ≥ 0`, given in double precision like every world position. Each frame
//! the planes are made relative to the eye in f64 (`d + n·eye`) before they go to the GPU in
//! f32, so a cut stays exact far from the origin. The vertex shader every technique shares
//! clips against them (`gl_ClipDistance`), so every pass, the pick pass included, ignores what
//! they cut away. Where a plane cuts a closed part (`CADR_INSTANCE_CLOSED`), its inside shows
//! through the cut as back faces, which are visible only where the cut removed what was in
//! front of them; with caps on, the shaded pass paints those with the plane's cap colour, lit
//! as the plane (optionally hatched), so the cut reads as a solid face. An open part shows no
//! cap (its inside, if seen, is shaded as it is). The cap keeps the depth of the face it is
//! painted on, so depth tests, occlusion culling and the edges mode's depth bias treat it like
//! any other surface; in the edge modes a caps pass paints the visible caps again over the
//! edge lines of that face (`PassSet::Shaded::caps_over_lines`). Picking a cap picks
//! the part that was cut, at the point where the plane cuts it (`cap_entry`): the pick pass
//! flags cap pixels and the host moves their depth to the plane.

use glam::{DVec3, DVec4};

/// The most section planes at once (the clip distances every device offers).
pub const MAX_SECTION_PLANES: usize = 6;

/// The cap colours of the planes, in order (linear RGBA).
pub const DEFAULT_CAP_COLORS: [[f32; 4]; MAX_SECTION_PLANES] = [
    [0.85, 0.20, 0.15, 1.0],
    [0.15, 0.55, 0.85, 1.0],
    [0.20, 0.70, 0.30, 1.0],
    [0.90, 0.70, 0.10, 1.0],
    [0.60, 0.30, 0.80, 1.0],
    [0.10, 0.70, 0.70, 1.0],
];

/// The section of a view: its planes and how cuts are capped.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    planes: Vec<DVec4>,
    cap_colors: [[f32; 4]; MAX_SECTION_PLANES],
    caps: bool,
    hatched: bool,
}

impl Default for Section {
    fn default() -> Self {
        Self {
            planes: Vec::new(),
            cap_colors: DEFAULT_CAP_COLORS,
            caps: true,
            hatched: false,
        }
    }
}

impl Section {
    /// No planes: nothing is cut.
    pub fn none() -> Self {
        Self::default()
    }

    /// Sets the planes, each `(nx, ny, nz, d)` keeping `n·p + d ≥ 0`; normals need not be unit
    /// length (each plane is scaled so that its normal is). At most [`MAX_SECTION_PLANES`],
    /// each finite with a non-zero normal; the error names the plane.
    pub fn set_planes(&mut self, planes: &[DVec4]) -> Result<(), String> {
        if planes.len() > MAX_SECTION_PLANES {
            return Err(format!(
                "{} section planes given; at most {MAX_SECTION_PLANES}",
                planes.len()
            ));
        }
        let mut normalised = Vec::with_capacity(planes.len());
        for (i, plane) in planes.iter().enumerate() {
            let length = plane.truncate().length();
            if !plane.is_finite() || !length.is_normal() {
                return Err(format!(
                    "section plane {i} ({}, {}, {}, {}) needs a finite, non-zero normal and a finite distance",
                    plane.x, plane.y, plane.z, plane.w
                ));
            }
            normalised.push(*plane / length);
        }
        self.planes = normalised;
        Ok(())
    }

    /// The planes, normals of unit length.
    pub fn planes(&self) -> &[DVec4] {
        &self.planes
    }

    /// Whether cuts through closed parts are capped (the default).
    pub fn caps(&self) -> bool {
        self.caps
    }

    /// Whether a cap can show to an eye at `eye`: caps are on and the eye is on the cut side
    /// of a plane, so that a view ray can cross a cut into a part (the host's counterpart of
    /// the test in `section_cap_plane`, `shaders/section.glsl`).
    pub fn caps_seen_from(&self, eye: DVec3) -> bool {
        self.caps
            && self
                .planes
                .iter()
                .any(|plane| plane.truncate().dot(eye) + plane.w < 0.0)
    }

    /// Caps cuts through closed parts, or shows their inside.
    pub fn set_caps(&mut self, caps: bool) {
        self.caps = caps;
    }

    /// Whether caps are hatched.
    pub fn hatched(&self) -> bool {
        self.hatched
    }

    /// Hatches the caps (diagonal lines on screen) or fills them plainly (the default).
    pub fn set_hatched(&mut self, hatched: bool) {
        self.hatched = hatched;
    }

    /// The cap colour of plane `index` (linear RGBA).
    pub fn cap_color(&self, index: usize) -> Option<[f32; 4]> {
        self.cap_colors.get(index).copied()
    }

    /// Sets the cap colour of plane `index`; false when there is no such slot.
    pub fn set_cap_color(&mut self, index: usize, color: [f32; 4]) -> bool {
        match self.cap_colors.get_mut(index) {
            Some(slot) if color.iter().all(|c| c.is_finite()) => {
                *slot = color.map(|c| c.clamp(0.0, 1.0));
                true
            }
            _ => false,
        }
    }

    /// Where the segment from `from` to `to` last crosses into the kept side of a plane it
    /// starts on the cut side of: where a cap seen from `from` at `to` lies (the f64
    /// counterpart of `section_cap_plane` in `shaders/section.glsl`). None when it crosses
    /// no plane that way, or ends where a plane cuts (nothing is drawn there).
    pub fn cap_entry(&self, from: DVec3, to: DVec3) -> Option<DVec3> {
        let mut entry: Option<f64> = None;
        for plane in &self.planes {
            let start = plane.truncate().dot(from) + plane.w;
            let end = plane.truncate().dot(to) + plane.w;
            if end < 0.0 {
                return None;
            }
            if start < 0.0 {
                let t = start / (start - end);
                entry = Some(entry.map_or(t, |e| e.max(t)));
            }
        }
        entry.map(|t| from.lerp(to, t))
    }

    /// The planes relative to `eye` as the shaders take them: `(n, d + n·eye)`, computed in f64
    /// and then rounded; unused slots keep everything.
    pub(crate) fn eye_relative(&self, eye: DVec3) -> [[f32; 4]; MAX_SECTION_PLANES] {
        let mut out = [[0.0, 0.0, 0.0, 1.0]; MAX_SECTION_PLANES];
        for (slot, plane) in out.iter_mut().zip(&self.planes) {
            let normal = plane.truncate();
            let distance = plane.w + normal.dot(eye);
            *slot = [
                normal.x as f32,
                normal.y as f32,
                normal.z as f32,
                distance as f32,
            ];
        }
        out
    }

    /// The colours the shaders take.
    pub(crate) fn colors(&self) -> [[f32; 4]; MAX_SECTION_PLANES] {
        self.cap_colors
    }

    /// The flags word the shaders take: plane count in bits 0-7, caps bit 8, hatching bit 9.
    pub(crate) fn flags(&self) -> u32 {
        self.planes.len() as u32 | (u32::from(self.caps) << 8) | (u32::from(self.hatched) << 9)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Test code: a failed unwrap is a failed test.
mod tests {
    use super::*;

    #[test]
    fn planes_are_checked_and_normalised() {
        let mut section = Section::none();
        section
            .set_planes(&[DVec4::new(0.0, 0.0, 2.0, -4.0)])
            .unwrap();
        assert_eq!(section.planes(), &[DVec4::new(0.0, 0.0, 1.0, -2.0)]);
        let zero = section.set_planes(&[DVec4::X, DVec4::ZERO]).unwrap_err();
        assert!(zero.contains("section plane 1"), "{zero}");
        let many = section.set_planes(&[DVec4::X; 7]).unwrap_err();
        assert!(many.contains("at most 6"), "{many}");
        let infinite = section.set_planes(&[DVec4::new(1.0, 0.0, 0.0, f64::NAN)]);
        assert!(infinite.is_err());
        assert_eq!(section.planes().len(), 1, "a refused set leaves the planes");
    }

    #[test]
    fn a_cap_lies_where_the_segment_last_enters_the_kept_side() {
        let mut section = Section::none();
        // Keeps x >= 1 and y >= 2.
        section
            .set_planes(&[
                DVec4::new(1.0, 0.0, 0.0, -1.0),
                DVec4::new(0.0, 2.0, 0.0, -4.0),
            ])
            .unwrap();
        let from = DVec3::new(0.0, 0.0, 0.0);
        // Crosses x = 1 at t = 0.25 and y = 2 at t = 0.5: the last is the cap.
        let entry = section.cap_entry(from, DVec3::new(4.0, 4.0, 8.0)).unwrap();
        assert!(
            (entry - DVec3::new(2.0, 2.0, 4.0)).length() < 1e-12,
            "{entry}"
        );
        // Starting on the kept side of both: no cut lies in front.
        assert_eq!(
            section.cap_entry(DVec3::new(2.0, 3.0, 0.0), DVec3::ONE * 9.0),
            None
        );
        // Ending on the cut side of a plane: nothing is drawn there.
        assert_eq!(section.cap_entry(from, DVec3::new(4.0, 1.0, 0.0)), None);
    }

    #[test]
    fn caps_show_only_to_an_eye_on_the_cut_side_of_a_plane() {
        let mut section = Section::none();
        section
            .set_planes(&[
                DVec4::new(0.0, 0.0, -1.0, 0.0),
                DVec4::new(1.0, 0.0, 0.0, 5.0),
            ])
            .unwrap();
        let above = DVec3::new(0.0, 0.0, 4.0);
        let below = DVec3::new(0.0, 0.0, -4.0);
        assert!(section.caps_seen_from(above), "z > 0 is cut away");
        assert!(!section.caps_seen_from(below), "kept by both planes");
        assert!(
            section.caps_seen_from(DVec3::new(-6.0, 0.0, -4.0)),
            "cut by the second plane"
        );
        section.set_caps(false);
        assert!(!section.caps_seen_from(above), "caps off");
        assert!(!Section::none().caps_seen_from(above), "no planes");
    }

    #[test]
    fn eye_relative_planes_stay_exact_far_from_the_origin() {
        // A plane 1e9 from the origin, the eye 0.25 in front of it: in f32 world coordinates
        // the distance would round to a multiple of 64; relative to the eye it is exact.
        let mut section = Section::none();
        section
            .set_planes(&[DVec4::new(1.0, 0.0, 0.0, -1.0e9)])
            .unwrap();
        let relative = section.eye_relative(DVec3::new(1.0e9 + 0.25, 5.0, 5.0));
        assert_eq!(relative[0], [1.0, 0.0, 0.0, 0.25]);
        assert_eq!(relative[1], [0.0, 0.0, 0.0, 1.0], "unused slots keep all");
        assert_eq!(section.flags(), 1 | 1 << 8);
    }
}
