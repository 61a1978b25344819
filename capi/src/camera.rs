//! Cameras in double precision: view and projection matrices, built by looking at a point or
//! by fitting bounds.

use cadr_core::render::{Camera, DEFAULT_DIRECTION};
use cadr_core::scene::Aabb;
use glam::{DMat4, DVec3};

use crate::args::{deliver, non_null, vector3};
use crate::bounds::CadrBounds;
use crate::error::{guard, CadrResult, Failure};

/// A camera: world-to-view and view-to-clip matrices, column-major doubles. The view looks
/// down -Z (right-handed); the projection follows Vulkan (y down, depth 0..1). Hosts may fill
/// it with their own matrices.
///
/// Frozen: a camera is its two matrices, and stays so within a major version.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CadrCamera {
    /// World to view space.
    pub view: [f64; 16],
    /// View to clip space.
    pub projection: [f64; 16],
}

impl From<Camera> for CadrCamera {
    fn from(camera: Camera) -> Self {
        Self {
            view: camera.view.to_cols_array(),
            projection: camera.projection.to_cols_array(),
        }
    }
}

impl CadrCamera {
    /// The core camera, with every value checked to be finite.
    pub(crate) fn to_core(self) -> Result<Camera, Failure> {
        for (name, values) in [
            ("camera.view", &self.view),
            ("camera.projection", &self.projection),
        ] {
            if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                return Err(Failure::invalid(format!("{name}[{i}] is not finite")));
            }
        }
        Ok(Camera {
            view: DMat4::from_cols_array(&self.view),
            projection: DMat4::from_cols_array(&self.projection),
        })
    }
}

/// A perspective camera at `eye` looking at `target` (+Y up, or +Z when looking along Y) with a
/// vertical field of view in degrees, `aspect` = width / height, and near and far distances.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or `CADR_RESULT_INVALID_ARGUMENT` (eye
/// equal to target, field of view outside 0..180, aspect or near not positive, far not beyond
/// near, non-finite values).
/// Ownership: the arrays are read during the call. Thread-safety: callable from any thread.
///
/// # Safety
/// `eye` and `target` are null or 3 readable doubles; `camera` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_camera_look_at(
    eye: *const f64,
    target: *const f64,
    fov_y_degrees: f64,
    aspect: f64,
    near: f64,
    far: f64,
    camera: *mut CadrCamera,
) -> CadrResult {
    guard(|| {
        // SAFETY: forwarded contract.
        let (eye, target) = unsafe { (vector3(eye, "eye")?, vector3(target, "target")?) };
        if eye.distance(target) <= 0.0 {
            return Err(Failure::invalid("eye and target are the same point"));
        }
        if !(fov_y_degrees > 0.0 && fov_y_degrees < 180.0) {
            return Err(Failure::invalid(format!(
                "fov_y_degrees is {fov_y_degrees}; it must lie between 0 and 180"
            )));
        }
        if !(aspect > 0.0 && aspect.is_finite()) {
            return Err(Failure::invalid(format!(
                "aspect is {aspect}; it must be positive"
            )));
        }
        if !(near > 0.0 && far > near && far.is_finite()) {
            return Err(Failure::invalid(format!(
                "near {near} and far {far}: need 0 < near < far"
            )));
        }
        let value = Camera::look_at(eye, target, fov_y_degrees, aspect, near, far);
        // SAFETY: camera is null or writable (the caller's contract).
        unsafe { deliver(camera, "camera", value.into()) }
    })
}

/// A camera that sees all of `bounds` from `direction` (NULL: front-right, above) for an image
/// of `aspect` = width / height. Empty bounds give a camera on the unit sphere.
///
/// Returns `CADR_RESULT_OK`, `CADR_RESULT_NULL_ARGUMENT` or `CADR_RESULT_INVALID_ARGUMENT`.
/// Ownership: the inputs are read during the call. Thread-safety: callable from any thread.
///
/// # Safety
/// `bounds` is null or readable; `direction` null or 3 readable doubles; `camera` null or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn cadr_camera_fit(
    bounds: *const CadrBounds,
    aspect: f64,
    direction: *const f64,
    camera: *mut CadrCamera,
) -> CadrResult {
    guard(|| {
        non_null(bounds, "bounds")?;
        // SAFETY: non-null and readable by contract.
        let bounds = unsafe { *bounds };
        let direction = if direction.is_null() {
            DEFAULT_DIRECTION
        } else {
            // SAFETY: forwarded contract.
            unsafe { vector3(direction, "direction") }?
        };
        if direction.length() == 0.0 {
            return Err(Failure::invalid("direction is the zero vector"));
        }
        if !(aspect > 0.0 && aspect.is_finite()) {
            return Err(Failure::invalid(format!(
                "aspect is {aspect}; it must be positive"
            )));
        }
        let aabb = Aabb {
            min: DVec3::from_array(bounds.min),
            max: DVec3::from_array(bounds.max),
        };
        let aabb = if aabb.min.is_finite() && aabb.max.is_finite() {
            aabb
        } else {
            Aabb::EMPTY
        };
        let value = Camera::fit(&aabb, aspect, direction);
        // SAFETY: camera is null or writable (the caller's contract).
        unsafe { deliver(camera, "camera", value.into()) }
    })
}
