//! The robots that ship with Hearth, embedded in the binary (no files, no downloads).

use std::path::Path;

use crate::error::{KinematicsError, Result};
use crate::model::{ChainSpec, RobotModel};
use crate::urdf::{LoadOptions, build};

/// A robot shipped with Hearth.
///
/// ```
/// use hearth_kinematics::{BUILTIN_ROBOTS, RobotModel};
/// let locobot = BUILTIN_ROBOTS.iter().find(|r| r.name == "locobot").unwrap();
/// assert!(locobot.urdf.contains("<robot"));
/// assert_eq!(RobotModel::builtin(locobot.name).unwrap().chains().len(), locobot.chains.len());
/// ```
#[derive(Clone, Copy, Debug)]
pub struct BuiltinRobot {
    /// Name to load it by (`--robot NAME`).
    pub name: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// The URDF text.
    pub urdf: &'static str,
    /// Named chains: (name, joints, tip link).
    pub chains: &'static [(&'static str, &'static [&'static str], &'static str)],
}

const PANDA_ARM: &[&str] = &[
    "panda_joint1",
    "panda_joint2",
    "panda_joint3",
    "panda_joint4",
    "panda_joint5",
    "panda_joint6",
    "panda_joint7",
];
const FETCH_ARM: &[&str] = &[
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];
const FETCH_ARM_WITH_TORSO: &[&str] = &[
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];

/// Every built-in robot.
///
/// ```
/// use hearth_kinematics::{BUILTIN_ROBOTS, RobotModel};
/// assert_eq!(BUILTIN_ROBOTS.len(), 4);
/// for robot in BUILTIN_ROBOTS {
///     assert_eq!(RobotModel::builtin(robot.name).unwrap().source_name(), format!("builtin:{}", robot.name));
/// }
/// ```
pub const BUILTIN_ROBOTS: &[BuiltinRobot] = &[
    BuiltinRobot {
        name: "panda",
        description: "Franka Emika Panda: 7-DOF arm with a parallel gripper",
        urdf: include_str!("../robots/panda.urdf"),
        chains: &[("arm", PANDA_ARM, "panda_hand_tcp")],
    },
    BuiltinRobot {
        name: "fetch",
        description: "Fetch: differential-drive base, torso lift, 7-DOF arm, pan/tilt head, parallel gripper",
        urdf: include_str!("../robots/fetch.urdf"),
        chains: &[
            ("arm_with_torso", FETCH_ARM_WITH_TORSO, "gripper_link"),
            ("arm", FETCH_ARM, "gripper_link"),
            ("head", &["head_pan_joint", "head_tilt_joint"], "head_camera_link"),
        ],
    },
    BuiltinRobot {
        name: "locobot",
        description: "LoCoBot: Kobuki differential-drive base, 5-DOF arm, pan/tilt camera, 1-beam LiDAR",
        urdf: include_str!("../robots/locobot.urdf"),
        chains: &[
            (
                "arm",
                &["joint_1", "joint_2", "joint_3", "joint_4", "joint_5"],
                "gripper_link",
            ),
            ("head", &["head_pan_joint", "head_tilt_joint"], "camera_link"),
        ],
    },
    BuiltinRobot {
        name: "turtlebot",
        description: "TurtleBot 2: Kobuki differential-drive base with a camera and a laser",
        urdf: include_str!("../robots/turtlebot.urdf"),
        chains: &[],
    },
];

/// Names of the built-in robots.
///
/// ```
/// assert!(hearth_kinematics::builtin_names().contains(&"fetch"));
/// ```
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN_ROBOTS.iter().map(|r| r.name).collect()
}

impl RobotModel {
    /// Loads a built-in robot by name: `panda`, `fetch`, `locobot`, `turtlebot`.
    ///
    /// ```
    /// let fetch = hearth_kinematics::RobotModel::builtin("fetch").unwrap();
    /// assert!(fetch.link_index("eyes").is_ok());
    /// assert!(hearth_kinematics::RobotModel::builtin("r2d2").is_err());
    /// ```
    pub fn builtin(name: &str) -> Result<Self> {
        let robot = BUILTIN_ROBOTS
            .iter()
            .find(|r| r.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| KinematicsError::UnknownRobot {
                name: name.to_owned(),
                known: builtin_names().join(", "),
            })?;
        let chains = robot
            .chains
            .iter()
            .map(|(n, joints, tip)| ChainSpec {
                name: (*n).to_owned(),
                joints: joints.iter().map(|j| (*j).to_owned()).collect(),
                tip: (*tip).to_owned(),
            })
            .collect();
        build(
            robot.urdf,
            &format!("builtin:{}", robot.name),
            None,
            &LoadOptions::default(),
            chains,
        )
    }

    /// A built-in robot by name, or a URDF file by path (anything ending in `.urdf` or
    /// containing a path separator).
    ///
    /// ```
    /// let panda = hearth_kinematics::RobotModel::load("panda").unwrap();
    /// assert_eq!(panda.name(), "panda");
    /// ```
    pub fn load(name_or_path: &str) -> Result<Self> {
        let looks_like_path = name_or_path.ends_with(".urdf")
            || name_or_path.ends_with(".xml")
            || name_or_path.contains(std::path::MAIN_SEPARATOR)
            || name_or_path.contains('/');
        if looks_like_path || Path::new(name_or_path).is_file() {
            Self::from_urdf_file(name_or_path)
        } else {
            Self::builtin(name_or_path)
        }
    }
}
