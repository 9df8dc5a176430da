//! The one seam between this crate's nalgebra `f64` poses and parry/rapier's glam `f32` poses.

use nalgebra::{Isometry3, Point3, Quaternion, Translation3, UnitQuaternion};
use parry3d::math::{Pose, Rotation, Vector};

/// Converts a kinematics pose to a parry/rapier pose (f64 → f32).
///
/// ```
/// use hearth_kinematics::{from_pose, to_pose};
/// use nalgebra::{Isometry3, Vector3};
/// let iso = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.0, 0.0, 0.5));
/// let back = from_pose(&to_pose(&iso));
/// assert!((back.translation.vector - iso.translation.vector).norm() < 1e-6);
/// ```
#[inline]
pub fn to_pose(iso: &Isometry3<f64>) -> Pose {
    let t = &iso.translation.vector;
    let q = iso.rotation.quaternion();
    Pose::from_parts(
        Vector::new(t.x as f32, t.y as f32, t.z as f32),
        Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32),
    )
}

/// Converts a kinematics point to a parry/rapier vector (f64 → f32).
///
/// ```
/// use hearth_kinematics::to_vector;
/// use nalgebra::Point3;
/// let v = to_vector(&Point3::new(1.0, 2.0, 3.0));
/// assert_eq!((v.x, v.y, v.z), (1.0, 2.0, 3.0));
/// ```
#[inline]
pub fn to_vector(p: &Point3<f64>) -> Vector {
    Vector::new(p.x as f32, p.y as f32, p.z as f32)
}

/// Converts a parry/rapier pose to a kinematics pose (f32 → f64).
///
/// ```
/// use hearth_kinematics::from_pose;
/// use parry3d::math::{Pose, Vector};
/// let iso = from_pose(&Pose::from_translation(Vector::new(0.5, -1.0, 2.0)));
/// assert_eq!(iso.translation.vector, nalgebra::Vector3::new(0.5, -1.0, 2.0));
/// assert_eq!(iso.rotation.angle(), 0.0);
/// ```
#[inline]
pub fn from_pose(pose: &Pose) -> Isometry3<f64> {
    let t = pose.translation;
    let r = pose.rotation;
    Isometry3::from_parts(
        Translation3::new(t.x as f64, t.y as f64, t.z as f64),
        UnitQuaternion::new_normalize(Quaternion::new(r.w as f64, r.x as f64, r.y as f64, r.z as f64)),
    )
}
