//! Bounds of point sets, as the GPU scene's parts, clusters, stand-ins and edge levels take
//! them: the box along the object's axes, and the sphere around the box's centre.

/// The least and most coordinates of `points` along each axis (infinite, min over max, where
/// there are none).
pub(super) fn box_of(points: impl IntoIterator<Item = [f32; 3]>) -> ([f32; 3], [f32; 3]) {
    points.into_iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(min, max), p| {
            (
                std::array::from_fn(|a| min[a].min(p[a])),
                std::array::from_fn(|a| max[a].max(p[a])),
            )
        },
    )
}

/// A sphere around `points` (centre, radius): the centre of their box, the radius the farthest
/// of them from it; all zeros where there are none.
pub(super) fn sphere_of(points: impl IntoIterator<Item = [f32; 3]> + Clone) -> [f32; 4] {
    let (min, max) = box_of(points.clone());
    if min[0] > max[0] {
        return [0.0; 4];
    }
    let center: [f32; 3] = std::array::from_fn(|a| 0.5 * (min[a] + max[a]));
    let radius = (points.into_iter())
        .map(|p| {
            let d: [f32; 3] = std::array::from_fn(|a| p[a] - center[a]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .fold(0.0_f32, f32::max);
    [center[0], center[1], center[2], radius]
}

/// Half the diagonal of the box around `points`.
pub(super) fn half_box_diagonal(points: impl IntoIterator<Item = [f32; 3]>) -> f32 {
    let (min, max) = box_of(points);
    (0..3)
        .map(|a| (max[a] - min[a]) * (max[a] - min[a]))
        .sum::<f32>()
        .sqrt()
        * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sphere_is_centred_on_the_box_and_reaches_the_farthest_point() {
        let points = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 4.0, 0.0]];
        assert_eq!(box_of(points), ([0.0; 3], [2.0, 4.0, 0.0]));
        let [x, y, z, r] = sphere_of(points);
        assert_eq!([x, y, z], [1.0, 2.0, 0.0]);
        assert!((r - 5.0_f32.sqrt()).abs() < 1e-6);
        assert!((half_box_diagonal(points) - 20.0_f32.sqrt() / 2.0).abs() < 1e-6);
        assert_eq!(sphere_of([]), [0.0; 4]);
    }
}
