//! Cameras in double precision; what reaches the GPU is relative to the eye.

use glam::{DMat4, DVec3};

use crate::scene::Aabb;

/// A perspective camera: view (world → eye) and projection (eye → Vulkan clip space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// World to view space, right-handed, looking down -Z.
    pub view: DMat4,
    /// View to clip space with Vulkan conventions (y down, depth 0..1).
    pub projection: DMat4,
}

/// The default viewing direction for fitted cameras: from front-right, above.
pub const DEFAULT_DIRECTION: DVec3 = DVec3::new(0.8, 0.7, 1.2);

/// Vertical field of view of fitted cameras, in degrees.
pub const DEFAULT_FOV_DEGREES: f64 = 40.0;

/// Splits f64 coordinates into an f32 high part and the f32 remainder: `high + low` equals the
/// input to about 2^-48 of its size, and the shader subtracts the eye's parts separately so
/// that positions relative to the eye keep that precision on the GPU.
pub fn split_f64(v: glam::DVec3) -> ([f32; 3], [f32; 3]) {
    let high = v.as_vec3();
    let low = (v - high.as_dvec3()).as_vec3();
    (high.to_array(), low.to_array())
}

impl Camera {
    /// World-space frustum planes (normals point inside; Vulkan depth 0..1).
    pub fn frustum_planes(&self) -> [[f64; 4]; 6] {
        let m: DMat4 = self.projection * self.view;
        let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
        [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2].map(|p| {
            let length = p.truncate().length();
            let p = if length > 0.0 { p / length } else { p };
            p.to_array()
        })
    }

    /// Where the eye is, in world space.
    pub fn eye(&self) -> DVec3 {
        self.view.inverse().w_axis.truncate()
    }

    /// A camera at `eye` looking at `target` with the +Y axis up.
    pub fn look_at(
        eye: DVec3,
        target: DVec3,
        fov_y_degrees: f64,
        aspect: f64,
        near: f64,
        far: f64,
    ) -> Self {
        let forward = (target - eye).normalize_or_zero();
        let up = if forward.cross(DVec3::Y).length_squared() < 1e-12 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let view = DMat4::look_at_rh(eye, target, up);
        let mut projection = DMat4::perspective_rh(fov_y_degrees.to_radians(), aspect, near, far);
        projection.y_axis.y *= -1.0;
        Self { view, projection }
    }

    /// A camera on a deterministic orbit around `bounds`: `turn` is the fraction of a full
    /// circle (0 to 1), the eye circles the centre at `distance` times the bounds' radius,
    /// somewhat above it, looking at the centre. At a distance of about 1 the frustum cuts
    /// the scene: what is behind the eye and beside the view is outside (the motion that
    /// culling must keep up with).
    pub fn orbit(bounds: &Aabb, aspect: f64, turn: f64, distance: f64) -> Self {
        let (center, radius) = if bounds.is_empty() {
            (DVec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(1e-6))
        };
        let angle = turn * std::f64::consts::TAU;
        let direction = DVec3::new(angle.cos(), 0.45, angle.sin()).normalize();
        let eye = center + direction * radius * distance;
        let near = radius * 1e-3;
        let far = radius * (distance + 1.5);
        Self::look_at(eye, center, DEFAULT_FOV_DEGREES, aspect, near, far)
    }

    /// A camera that sees all of `bounds` from `direction`, for an image of `aspect` (width/height):
    /// the eye moves back along `direction` until every corner of the box is inside the view.
    pub fn fit(bounds: &Aabb, aspect: f64, direction: DVec3) -> Self {
        let (center, radius) = if bounds.is_empty() {
            (DVec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(1e-6))
        };
        let backward = direction.normalize_or(DVec3::Z);
        let up_hint = if backward.cross(DVec3::Y).length_squared() < 1e-12 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = up_hint.cross(backward).normalize();
        let up = backward.cross(right);
        let tan_y = (DEFAULT_FOV_DEGREES.to_radians() * 0.5).tan();
        let tan_x = tan_y * aspect;
        let mut distance: f64 = 0.0;
        let extent = if bounds.is_empty() {
            DVec3::splat(1.0)
        } else {
            bounds.max - center
        };
        for corner in 0..8 {
            let sign = |bit: i32| if corner & bit == 0 { -1.0 } else { 1.0 };
            let p = DVec3::new(sign(1) * extent.x, sign(2) * extent.y, sign(4) * extent.z);
            // The eye must be far enough back that the corner falls within both half-angles.
            let needed =
                (p.dot(right).abs() / tan_x).max(p.dot(up).abs() / tan_y) + p.dot(backward);
            distance = distance.max(needed);
        }
        let distance = (distance * 1.05).max(radius * 1e-3);
        let eye = center + backward * distance;
        let near = (distance - radius * 1.05).max(distance * 1e-3);
        let far = distance + radius * 1.05;
        Self::look_at(eye, center, DEFAULT_FOV_DEGREES, aspect, near, far)
    }
}
