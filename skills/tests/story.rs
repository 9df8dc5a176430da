//! The mobile-manipulation story end to end in a generated home (kinematic execution: the
//! physics run takes tens of seconds in the dev profile; `hearth demo --seeds` measures it).

use hearth_skills::Execution;
use hearth_skills::story::{StoryOptions, run_story, run_story_in};

fn kinematic(seed: u64) -> StoryOptions {
    StoryOptions {
        seed,
        execution: Execution::Kinematic,
        ..Default::default()
    }
}

#[test]
fn the_story_runs_end_to_end_and_is_deterministic() {
    let a = run_story(&kinematic(0));
    for s in &a.stages {
        eprintln!("{:<20} {:>5} {:>6.2} s  {}", s.name, s.success, s.wall_time, s.detail);
    }
    assert!(a.success, "{:?}", a.failure);
    assert!(a.failure.is_none());
    let names: Vec<&str> = a.stages.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "setup",
            "navigate_to_cabinet",
            "open_drawer",
            "navigate_to_sink",
            "grasp_dish",
            "place_in_sink"
        ]
    );
    assert!(a.trajectory.len() >= 6);
    assert!(a.trajectory.iter().all(|s| s.joints.len() == a.joint_names.len()));
    let b = run_story(&kinematic(0));
    assert_eq!(a.trajectory_hash, b.trajectory_hash);
    assert_eq!(a.dish_position, b.dish_position);
}

#[test]
fn a_home_without_a_kitchen_counter_fails_setup_with_a_reason() {
    let mut home = hearth_sim::scene::generate(&hearth_sim::scene::GenerateOptions {
        seed: 0,
        rooms: 2,
        ..Default::default()
    })
    .unwrap();
    home.objects.retain(|o| o.category != "counter");
    let r = run_story_in(home, &kinematic(0));
    assert!(!r.success);
    let f = r.failure.unwrap();
    assert_eq!(
        (f.stage.as_str(), f.reason.as_str()),
        ("setup", "unreachable"),
        "{}",
        f.message
    );
    assert!(f.message.contains("counter"), "{}", f.message);
}
