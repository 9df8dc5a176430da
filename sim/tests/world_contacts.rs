//! Contact readout on a link whose collider is a compound (several URDF collision elements).

use hearth_sim::kinematics::RobotModel;
use hearth_sim::world::{SpawnOptions, World, WorldConfig};
use nalgebra::Isometry3;

/// One link, two 10 cm boxes 40 cm apart (a compound collider), a dumbbell lying on the ground.
const DUMBBELL: &str = r#"<robot name="dumbbell">
  <link name="bar">
    <inertial><mass value="1.0"/><inertia ixx="0.02" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.2 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
    <collision><origin xyz="-0.2 0 0"/><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
</robot>"#;

#[test]
fn contact_points_of_compound_colliders_are_in_world_coordinates() {
    let model = RobotModel::from_urdf_str(DUMBBELL, None).unwrap();
    let mut world = World::new(WorldConfig::default()).unwrap();
    let bar = world
        .spawn_model(&model, &Isometry3::translation(1.0, 2.0, 0.06), SpawnOptions::free())
        .unwrap();
    for _ in 0..30 {
        world.step();
    }
    let contacts = world.contacts(bar).unwrap();
    assert!(!contacts.is_empty(), "the dumbbell rests on the ground");
    for c in &contacts {
        // On the ground plane, under one of the two boxes (x = 1 ± 0.2, within half a box).
        assert!(
            c.point.z.abs() < 0.01,
            "contact point {:?} is not on the ground",
            c.point
        );
        let dx = (c.point.x - 1.0).abs();
        assert!(
            (dx - 0.2).abs() <= 0.051,
            "contact point {:?} is not under a box",
            c.point
        );
        assert!((c.point.y - 2.0).abs() <= 0.051, "contact point {:?}", c.point);
    }
}
