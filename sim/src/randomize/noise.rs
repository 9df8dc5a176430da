//! Pose perturbations (robot start, camera mount) and depth-image noise.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::config::PoseRandomization;
use super::sampling::standard_normal;
use crate::scene::{SceneFile, SceneMaps};

/// How many perturbed robot start poses are tried before the original is kept.
///
/// ```
/// assert!(hearth_sim::randomize::START_POSE_TRIES >= 1);
/// ```
pub const START_POSE_TRIES: usize = 20;

/// Depth-image noise: zero-mean Gaussian with a standard deviation that grows with the square
/// of the distance, `σ(d) = std + quadratic · d²`, plus dropout to 0 (no return).
///
/// The quadratic growth follows structured-light and time-of-flight sensor models (axial
/// noise of the first Kinect measured as σ ≈ 1.2 mm + 1.9 mm·(d − 0.4 m)²: Nguyen, Izadi and
/// Lovell, "Modeling Kinect Sensor Noise", 3DIMPVT 2012), simplified to `d²`.
///
/// ```
/// use hearth_sim::randomize::DepthNoise;
/// let kinect_like = DepthNoise { std: 0.0012, quadratic: 0.0019, dropout: 0.0 };
/// assert!((kinect_like.std_at(2.0) - (0.0012 + 0.0019 * 4.0)).abs() < 1e-12);
/// assert!(DepthNoise::NONE.is_none());
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DepthNoise {
    /// Standard deviation at any distance, m.
    pub std: f64,
    /// Growth of the standard deviation with the squared distance, m/m².
    pub quadratic: f64,
    /// Probability that a pixel reads 0.
    pub dropout: f64,
}

impl DepthNoise {
    /// No noise.
    ///
    /// ```
    /// # use hearth_sim::randomize::DepthNoise;
    /// assert_eq!(DepthNoise::NONE, DepthNoise::default());
    /// assert_eq!(DepthNoise::NONE.std_at(3.0), 0.0);
    /// ```
    pub const NONE: DepthNoise = DepthNoise {
        std: 0.0,
        quadratic: 0.0,
        dropout: 0.0,
    };

    /// Whether nothing is drawn.
    ///
    /// ```
    /// # use hearth_sim::randomize::DepthNoise;
    /// assert!(DepthNoise::default().is_none());
    /// assert!(!DepthNoise { dropout: 0.01, ..DepthNoise::NONE }.is_none());
    /// ```
    pub fn is_none(&self) -> bool {
        self.std == 0.0 && self.quadratic == 0.0 && self.dropout == 0.0
    }

    /// Standard deviation at distance `d`.
    ///
    /// ```
    /// # use hearth_sim::randomize::DepthNoise;
    /// let n = DepthNoise { std: 0.001, quadratic: 0.002, dropout: 0.0 };
    /// assert!((n.std_at(0.0) - 0.001).abs() < 1e-15);
    /// assert!((n.std_at(3.0) - 0.019).abs() < 1e-12);
    /// ```
    pub fn std_at(&self, d: f64) -> f64 {
        self.std + self.quadratic * d * d
    }
}

/// Adds [`DepthNoise`] to a depth buffer in place (metres, 0 = no return, as
/// [`Frame::depth`](crate::sensors::Frame)). Pixels reading 0 stay 0; noisy depths are clamped
/// at 0. Every pixel draws the same numbers whether it has a return or not, so the noise of a
/// pixel depends only on the stream and its index. Does not allocate.
///
/// ```
/// use hearth_sim::randomize::{DepthNoise, add_depth_noise};
/// use rand::SeedableRng;
/// let mut depth = vec![2.0f32; 1000];
/// depth[0] = 0.0;
/// let noise = DepthNoise { std: 0.01, quadratic: 0.0, dropout: 0.1 };
/// add_depth_noise(&mut depth, &noise, &mut rand_pcg::Pcg64Mcg::seed_from_u64(1));
/// assert_eq!(depth[0], 0.0);
/// let dropped = depth.iter().filter(|&&d| d == 0.0).count();
/// assert!(dropped > 50 && dropped < 160);
/// assert!(depth.iter().all(|&d| d == 0.0 || (d - 2.0).abs() < 0.1));
/// ```
pub fn add_depth_noise(depth: &mut [f32], noise: &DepthNoise, rng: &mut Pcg64Mcg) {
    if noise.is_none() {
        return;
    }
    for d in depth.iter_mut() {
        let dropped = noise.dropout > 0.0 && rng.random::<f64>() < noise.dropout;
        let g = standard_normal(rng);
        if *d <= 0.0 {
            continue;
        }
        if dropped {
            *d = 0.0;
        } else {
            let x = f64::from(*d);
            *d = (x + g * noise.std_at(x)).max(0.0) as f32;
        }
    }
}

/// A planar pose perturbed by zero-mean Gaussian noise: `xy_std` on each of x and y,
/// `yaw_std` on the heading.
///
/// ```
/// use hearth_sim::randomize::perturb_pose2d;
/// use rand::SeedableRng;
/// let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
/// assert_eq!(perturb_pose2d([1.0, 2.0], 0.5, 0.0, 0.0, &mut rng), ([1.0, 2.0], 0.5));
/// let (p, _) = perturb_pose2d([1.0, 2.0], 0.5, 0.1, 0.1, &mut rng);
/// assert!(p != [1.0, 2.0] && (p[0] - 1.0).abs() < 1.0);
/// ```
pub fn perturb_pose2d(xy: [f64; 2], yaw: f64, xy_std: f64, yaw_std: f64, rng: &mut Pcg64Mcg) -> ([f64; 2], f64) {
    let (gx, gy, gy2) = (standard_normal(rng), standard_normal(rng), standard_normal(rng));
    (
        [xy[0] + xy_std * gx, xy[1] + xy_std * gy],
        wrap_angle(yaw + yaw_std * gy2),
    )
}

fn wrap_angle(a: f64) -> f64 {
    let w = (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    if w.is_finite() { w } else { 0.0 }
}

/// Perturbs the scene's robot start pose ([`PoseRandomization::robot_xy_std`] and
/// `robot_yaw_std`). With `maps`, a perturbed position must be traversable
/// ([`SceneMaps::is_traversable`]): up to [`START_POSE_TRIES`] draws are tried and the original
/// pose is kept when none is. Returns whether the pose changed.
///
/// ```
/// use hearth_sim::randomize::{PoseRandomization, perturb_robot_start};
/// use hearth_sim::scene::{RobotPlacement, SceneFile};
/// use rand::SeedableRng;
/// let mut scene = SceneFile::empty("open");
/// scene.robot = Some(RobotPlacement { name: "fetch".into(), position: [0.0, 0.0, 0.0], yaw: 0.0 });
/// let pose = PoseRandomization { robot_xy_std: 0.2, robot_yaw_std: 0.3, ..Default::default() };
/// let moved = perturb_robot_start(&mut scene, &pose, None, &mut rand_pcg::Pcg64Mcg::seed_from_u64(1));
/// assert!(moved && scene.robot.unwrap().position[0] != 0.0);
/// ```
pub fn perturb_robot_start(
    scene: &mut SceneFile,
    pose: &PoseRandomization,
    maps: Option<&SceneMaps>,
    rng: &mut Pcg64Mcg,
) -> bool {
    let Some(robot) = scene.robot.as_mut() else {
        return false;
    };
    if pose.robot_xy_std == 0.0 && pose.robot_yaw_std == 0.0 {
        return false;
    }
    let xy = [robot.position[0], robot.position[1]];
    for _ in 0..START_POSE_TRIES {
        let (p, yaw) = perturb_pose2d(xy, robot.yaw, pose.robot_xy_std, pose.robot_yaw_std, rng);
        if maps.is_none_or(|m| m.is_traversable(p)) {
            robot.position[0] = p[0];
            robot.position[1] = p[1];
            robot.yaw = yaw;
            return true;
        }
    }
    false
}

/// A camera mount offset: Gaussian translation (`camera_xyz_std` per axis) and roll, pitch and
/// yaw (`camera_rpy_std` each), in the camera's optical frame. Render with it as
/// `camera.render_from(&world, &(camera.pose(&world)? * offset), modalities)`.
///
/// ```
/// use hearth_sim::randomize::{PoseRandomization, camera_offset};
/// use rand::SeedableRng;
/// let pose = PoseRandomization { camera_xyz_std: 0.01, camera_rpy_std: 0.02, ..Default::default() };
/// let o = camera_offset(&pose, &mut rand_pcg::Pcg64Mcg::seed_from_u64(5));
/// assert!(o.translation.vector.norm() > 0.0 && o.translation.vector.norm() < 0.1);
/// let none = camera_offset(&Default::default(), &mut rand_pcg::Pcg64Mcg::seed_from_u64(5));
/// assert_eq!(none, nalgebra::Isometry3::identity());
/// ```
pub fn camera_offset(pose: &PoseRandomization, rng: &mut Pcg64Mcg) -> Isometry3<f64> {
    if pose.camera_xyz_std == 0.0 && pose.camera_rpy_std == 0.0 {
        return Isometry3::identity();
    }
    let mut g = [0.0; 6];
    for x in &mut g {
        *x = standard_normal(rng);
    }
    let t = pose.camera_xyz_std;
    let r = pose.camera_rpy_std;
    Isometry3::from_parts(
        Translation3::new(t * g[0], t * g[1], t * g[2]),
        UnitQuaternion::from_euler_angles(r * g[3], r * g[4], r * g[5]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn depth_noise_grows_with_distance() {
        let noise = DepthNoise {
            std: 0.0,
            quadratic: 0.01,
            dropout: 0.0,
        };
        let spread = |d: f32| {
            let mut buf = vec![d; 4000];
            add_depth_noise(&mut buf, &noise, &mut Pcg64Mcg::seed_from_u64(9));
            let n = buf.len() as f64;
            let mean = buf.iter().map(|&x| f64::from(x)).sum::<f64>() / n;
            (buf.iter().map(|&x| (f64::from(x) - mean).powi(2)).sum::<f64>() / n).sqrt()
        };
        let (near, far) = (spread(1.0), spread(4.0));
        assert!((near - 0.01).abs() < 0.001, "{near}");
        assert!((far - 0.16).abs() < 0.015, "{far}");
    }

    #[test]
    fn angles_wrap() {
        let w = wrap_angle(3.0 * std::f64::consts::PI);
        assert!((w.abs() - std::f64::consts::PI).abs() < 1e-9);
        assert!((wrap_angle(0.5) - 0.5).abs() < 1e-12);
    }
}
