//! The `hearth` binary end to end: `kin info`, `kin fk`, `kin ik`, `bench kin`, `demo`, and the
//! errors a user meets (bad `--q`, unknown robot, missing or malformed URDF), which must exit non-zero
//! with a message and never a panic.

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn hearth(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hearth"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("cannot run hearth {args:?}: {e}"))
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `hearth args`, which must succeed, and parses its stdout as JSON.
#[track_caller]
fn json_ok(args: &[&str]) -> Value {
    let o = hearth(args);
    assert!(
        o.status.success(),
        "hearth {args:?} failed ({}):\n{}",
        o.status,
        stderr(&o)
    );
    serde_json::from_str(&stdout(&o))
        .unwrap_or_else(|e| panic!("hearth {args:?}: stdout is not JSON ({e}):\n{}", stdout(&o)))
}

/// Runs `hearth args`, which must fail cleanly; returns its stderr.
#[track_caller]
fn fails(args: &[&str]) -> String {
    let o = hearth(args);
    let err = stderr(&o);
    assert!(
        !o.status.success(),
        "hearth {args:?} should fail, but exited 0:\n{}",
        stdout(&o)
    );
    assert!(!err.contains("panicked"), "hearth {args:?} panicked:\n{err}");
    assert_ne!(o.status.code(), Some(101), "exit code 101 is a Rust panic: {err}");
    assert!(o.status.code().is_some(), "killed by a signal: {:?}", o.status);
    assert!(!err.trim().is_empty(), "hearth {args:?} failed without a message");
    err
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hearth_cli_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `kin info --robot panda --json`.
fn panda_info() -> Value {
    json_ok(&["kin", "info", "--robot", "panda", "--json"])
}

fn movable_joints(info: &Value) -> Vec<String> {
    info["movable_joints"]
        .as_array()
        .expect("movable_joints is an array")
        .iter()
        .map(|v| v.as_str().expect("joint names are strings").to_owned())
        .collect()
}

fn list(q: &[f64]) -> String {
    q.iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(",")
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap_or_else(|| panic!("expected an array, got {v}"));
    assert_eq!(a.len(), 3, "{v}");
    [0, 1, 2].map(|i| a[i].as_f64().unwrap())
}

fn vec4(v: &Value) -> [f64; 4] {
    let a = v.as_array().unwrap_or_else(|| panic!("expected an array, got {v}"));
    assert_eq!(a.len(), 4, "{v}");
    [0, 1, 2, 3].map(|i| a[i].as_f64().unwrap())
}

/// Angle between two unit quaternions (x, y, z, w).
fn quat_angle(a: [f64; 4], b: [f64; 4]) -> f64 {
    let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum::<f64>().abs().min(1.0);
    2.0 * dot.acos()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// `kin fk` for panda at `q`: (position, quat_xyzw) of `link`.
fn panda_fk(q: &[f64], link: &str) -> ([f64; 3], [f64; 4]) {
    let out = json_ok(&["kin", "fk", "--robot", "panda", "--q", &list(q), "--json"]);
    let l = &out["links"][link];
    assert!(l.is_object(), "no link {link} in fk output: {out}");
    (vec3(&l["position"]), vec4(&l["quat_xyzw"]))
}

#[test]
fn kin_info_json() {
    let info = panda_info();
    assert_eq!(info["name"], "panda");

    let links: Vec<&str> = info["links"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for l in [
        "panda_link0",
        "panda_link1",
        "panda_link8",
        "panda_hand",
        "panda_hand_tcp",
    ] {
        assert!(links.contains(&l), "missing link {l}: {links:?}");
    }
    assert_eq!(info["root"], "panda_link0");

    let joints = info["joints"].as_array().expect("joints is an array");
    assert_eq!(joints.len(), links.len() - 1, "a tree has one joint per non-root link");
    for j in joints {
        for key in ["name", "type", "parent", "child", "limits"] {
            assert!(j.get(key).is_some(), "joint without `{key}`: {j}");
        }
        let parent = j["parent"].as_str().unwrap();
        let child = j["child"].as_str().unwrap();
        assert!(links.contains(&parent) && links.contains(&child), "{j}");
        let kind = j["type"].as_str().unwrap();
        assert!(["revolute", "continuous", "prismatic", "fixed"].contains(&kind), "{j}");
        if kind == "fixed" {
            assert!(j["limits"].is_null(), "{j}");
        } else {
            for key in ["lower", "upper", "velocity", "effort"] {
                assert!(j["limits"].get(key).is_some(), "limits without `{key}`: {j}");
            }
        }
    }
    let j1 = joints
        .iter()
        .find(|j| j["name"] == "panda_joint1")
        .expect("panda_joint1");
    assert_eq!(j1["type"], "revolute");
    assert_eq!(j1["parent"], "panda_link0");
    assert_eq!(j1["child"], "panda_link1");
    assert!((j1["limits"]["lower"].as_f64().unwrap() + 2.8973).abs() < 1e-3, "{j1}");
    assert!((j1["limits"]["upper"].as_f64().unwrap() - 2.8973).abs() < 1e-3, "{j1}");
    let f2 = joints
        .iter()
        .find(|j| j["name"] == "panda_finger_joint2")
        .expect("panda_finger_joint2");
    assert_eq!(f2["mimic"]["joint"], "panda_finger_joint1", "{f2}");

    let movable = movable_joints(&info);
    assert_eq!(info["dof"].as_u64().unwrap() as usize, movable.len());
    assert_eq!(
        movable.len(),
        8,
        "7 arm joints + 1 finger (the other finger mimics): {movable:?}"
    );
    for i in 1..=7 {
        assert_eq!(movable[i - 1], format!("panda_joint{i}"));
    }
    assert!(
        !movable.contains(&"panda_finger_joint2".to_owned()),
        "mimic joints are not variables"
    );

    // The human-readable form works too.
    let o = hearth(&["kin", "info", "--robot", "panda"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("panda_joint7"));
}

#[test]
fn kin_fk_json_at_zero() {
    let dof = movable_joints(&panda_info()).len();
    let q = vec![0.0; dof];
    let out = json_ok(&["kin", "fk", "--robot", "panda", "--q", &list(&q), "--json"]);
    let links = out["links"].as_object().expect("links is an object");
    assert_eq!(links.len(), panda_info()["links"].as_array().unwrap().len());

    let l0 = &links["panda_link0"];
    assert!(dist(vec3(&l0["position"]), [0.0; 3]) < 1e-12, "{l0}");
    assert!(quat_angle(vec4(&l0["quat_xyzw"]), [0.0, 0.0, 0.0, 1.0]) < 1e-9, "{l0}");

    let l1 = &links["panda_link1"];
    assert!(dist(vec3(&l1["position"]), [0.0, 0.0, 0.333]) < 1e-9, "{l1}");
    assert!(quat_angle(vec4(&l1["quat_xyzw"]), [0.0, 0.0, 0.0, 1.0]) < 1e-9, "{l1}");

    // The flange at zero: x = 0.0825 - 0.0825 + 0.088, z = 0.333 + 0.316 + 0.384 - 0.107,
    // flipped by π about x.
    let l8 = &links["panda_link8"];
    assert!(dist(vec3(&l8["position"]), [0.088, 0.0, 0.926]) < 1e-6, "{l8}");
    assert!(quat_angle(vec4(&l8["quat_xyzw"]), [1.0, 0.0, 0.0, 0.0]) < 1e-6, "{l8}");
    for (name, pose) in links {
        let q = vec4(&pose["quat_xyzw"]);
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((n - 1.0).abs() < 1e-9, "{name}: quaternion not unit: {q:?}");
    }

    // Joint 1 turns everything above link 0 about z.
    let mut q = vec![0.0; dof];
    q[0] = std::f64::consts::FRAC_PI_2;
    let (p, _) = panda_fk(&q, "panda_link8");
    assert!(dist(p, [0.0, 0.088, 0.926]) < 1e-6, "{p:?}");
}

#[test]
fn kin_fk_rejects_a_wrong_length_q() {
    let dof = movable_joints(&panda_info()).len();
    let err = fails(&["kin", "fk", "--robot", "panda", "--q", "0,0,0"]);
    assert!(
        err.contains(&format!("{dof} values")),
        "should name the expected count {dof}: {err}"
    );
    assert!(err.contains("panda_joint1"), "should list the joints: {err}");

    let too_many = list(&vec![0.0; dof + 1]);
    let err = fails(&["kin", "fk", "--robot", "panda", "--q", &too_many]);
    assert!(err.contains(&format!("{dof}")), "{err}");
}

#[test]
fn kin_fk_rejects_a_non_number() {
    let err = fails(&["kin", "fk", "--robot", "panda", "--q", "0,abc"]);
    assert!(err.contains("abc"), "should name the bad item: {err}");

    let dof = movable_joints(&panda_info()).len();
    let mut q: Vec<String> = vec!["0".into(); dof];
    q[2] = "nan".into();
    let err = fails(&["kin", "fk", "--robot", "panda", "--q", &q.join(",")]);
    assert!(err.contains("panda_joint3"), "should name the non-finite joint: {err}");
}

#[test]
fn kin_ik_reproduces_an_fk_pose() {
    let movable = movable_joints(&panda_info());
    let mut q_goal = vec![0.0; movable.len()];
    for (i, v) in [0.3, -0.4, 0.2, -2.0, 0.1, 1.8, 0.6].iter().enumerate() {
        q_goal[i] = *v;
    }
    let (p, r) = panda_fk(&q_goal, "panda_hand_tcp");
    let pose = list(&[p[0], p[1], p[2], r[0], r[1], r[2], r[3]]);

    let sol = json_ok(&[
        "kin",
        "ik",
        "--robot",
        "panda",
        "--tip",
        "panda_hand_tcp",
        "--pose",
        &pose,
        "--json",
    ]);
    assert_eq!(sol["success"], true, "{sol}");
    let names: Vec<&str> = sol["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let values: Vec<f64> = sol["q"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(names.len(), values.len(), "{sol}");
    assert_eq!(names.len(), 7, "the arm chain: {names:?}");
    assert!(sol["position_error"].as_f64().unwrap() <= 1e-3, "{sol}");

    // Put the solution into a full configuration and check it through `kin fk`.
    let mut q = vec![0.0; movable.len()];
    for (n, v) in names.iter().zip(&values) {
        let i = movable
            .iter()
            .position(|m| m == n)
            .unwrap_or_else(|| panic!("{n} is not a movable joint"));
        q[i] = *v;
    }
    let (p2, r2) = panda_fk(&q, "panda_hand_tcp");
    assert!(dist(p, p2) < 2e-3, "position: target {p:?}, reached {p2:?}");
    assert!(quat_angle(r, r2) < 2e-2, "orientation: target {r:?}, reached {r2:?}");
}

#[test]
fn kin_ik_unreachable_pose_fails() {
    let err = fails(&[
        "kin",
        "ik",
        "--robot",
        "panda",
        "--tip",
        "panda_hand_tcp",
        "--pose",
        "5,0,0.5,0,0,0,1",
        "--json",
    ]);
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn unknown_robot_name_fails_cleanly() {
    let err = fails(&["kin", "info", "--robot", "does_not_exist"]);
    assert!(err.contains("does_not_exist"), "should name the robot: {err}");
    assert!(err.contains("panda"), "should list the built-in robots: {err}");
    let err = fails(&["kin", "fk", "--robot", "does_not_exist", "--q", "0"]);
    assert!(err.contains("does_not_exist"), "{err}");
}

#[test]
fn missing_urdf_file_fails_naming_the_path() {
    let err = fails(&["kin", "info", "--robot", "/nonexistent/file.urdf"]);
    assert!(err.contains("/nonexistent/file.urdf"), "should name the path: {err}");
}

#[test]
fn malformed_urdf_file_fails_naming_the_path() {
    let dir = temp_dir("malformed");
    let path = dir.join("broken.urdf");
    std::fs::write(&path, r#"<robot name="broken"><link name="a"><visual></link></robot>"#).unwrap();
    let p = path.to_str().unwrap();
    let err = fails(&["kin", "info", "--robot", p, "--json"]);
    assert!(err.contains("broken.urdf"), "should name the file: {err}");

    // And a well-formed file with a semantic error.
    let path2 = dir.join("dangling.urdf");
    std::fs::write(
        &path2,
        r#"<robot name="r"><link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="ghost"/></joint></robot>"#,
    )
    .unwrap();
    let err = fails(&["kin", "info", "--robot", path2.to_str().unwrap()]);
    assert!(err.contains("ghost") && err.contains("dangling.urdf"), "{err}");

    // A valid file loads through the same path.
    let path3 = dir.join("ok.urdf");
    std::fs::write(
        &path3,
        r#"<robot name="pendulum"><link name="a"/><link name="b"/>
           <joint name="hinge" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 1 0"/>
           <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#,
    )
    .unwrap();
    let info = json_ok(&["kin", "info", "--robot", path3.to_str().unwrap(), "--json"]);
    assert_eq!(info["dof"], 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_kin_writes_json() {
    let dir = temp_dir("bench");
    let path = dir.join("bench.json");
    let o = hearth(&[
        "bench",
        "kin",
        "--robot",
        "panda",
        "--samples",
        "20",
        "--json",
        path.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "bench failed: {}", stderr(&o));
    let text = std::fs::read_to_string(&path).expect("bench wrote its JSON file");
    let report: Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"));
    for key in ["fk_ns_median", "jacobian_ns_median", "ik_us_median", "ik_us_p95"] {
        let v = report[key]
            .as_f64()
            .unwrap_or_else(|| panic!("`{key}` missing or not a number: {report}"));
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    let rate = report["ik_success_rate"].as_f64().expect("ik_success_rate");
    assert!((0.0..=1.0).contains(&rate), "{rate}");
    assert!(report["ik_us_p95"].as_f64().unwrap() >= report["ik_us_median"].as_f64().unwrap());
    assert_eq!(report["ik_samples"], 20, "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_plan_refuses_unreadable_and_empty_inputs() {
    let empty = temp_dir("plan_empty");
    let missing = empty.join("missing.json");
    let err = fails(&["bench", "plan", "--problems", missing.to_str().unwrap()]);
    // The I/O error's message appears once, after the file's name.
    assert!(err.contains("cannot read"), "{err}");
    assert_eq!(err.matches("os error 2").count(), 1, "{err}");
    // A folder without problem files, and a file with an empty list, plan nothing: an error.
    let err = fails(&["bench", "plan", "--problems", empty.to_str().unwrap()]);
    assert!(err.contains("no problems to plan in"), "{err}");
    let file = empty.join("none.json");
    let none = r#"{"robot": "panda", "family": "f", "joint_names": ["panda_joint1"], "problems": []}"#;
    std::fs::write(&file, none).unwrap();
    let err = fails(&["bench", "plan", "--problems", file.to_str().unwrap()]);
    assert!(err.contains("no problems to plan in"), "{err}");
    std::fs::remove_dir_all(&empty).unwrap();
}

/// `--urdf ROBOT=PATH` plans a problem set's robot with another URDF's model: the built-in
/// Panda's own file gives the built-in model's plan, a model without collision geometry plans
/// through the table, and bad arguments are refused before any plan.
#[test]
fn bench_plan_takes_another_urdf() {
    let dir = temp_dir("plan_urdf");
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/planning/tests/data/panda_table_pick.json");
    let builtin = concat!(env!("CARGO_MANIFEST_DIR"), "/kinematics/robots/panda.urdf");
    let text = std::fs::read_to_string(builtin).unwrap();
    let bare = dir.join("panda_bare.urdf");
    let mut stripped = String::new();
    let mut rest = text.as_str();
    while let Some(at) = rest.find("<collision") {
        stripped.push_str(&rest[..at]);
        let end = rest[at..].find("</collision>").unwrap() + at + "</collision>".len();
        rest = &rest[end..];
    }
    stripped.push_str(rest);
    assert!(!stripped.contains("<collision") && stripped.len() < text.len());
    std::fs::write(&bare, &stripped).unwrap();
    let common = [
        "bench",
        "plan",
        "--problems",
        data,
        "--only",
        "table_pick:1",
        "--warm-up",
        "0",
        "--shortcut",
        "none",
        "--iterations",
        "100000",
        "--time-limit",
        "inf",
        "--seed",
        "4",
    ];
    let run = |extra: &[&str], name: &str| {
        let path = dir.join(name);
        let args = [&common[..], extra, &["--json", path.to_str().unwrap()][..]].concat();
        let o = hearth(&args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        (stderr(&o), v["results"][0].clone())
    };
    let (_, own) = run(&[], "builtin.json");
    let same_file = format!("panda={builtin}");
    let (err, file) = run(&["--urdf", &same_file], "file.json");
    assert!(err.contains("model from") && err.contains("panda.urdf"), "{err}");
    assert_eq!(own["success"], Value::Bool(true), "{own}");
    for key in ["success", "iterations", "plan_checks", "path_length"] {
        assert_eq!(own[key], file[key], "{key}: {own} against {file}");
    }
    // Without collision geometry nothing blocks the straight line from start to goal.
    let bare_arg = format!("panda={}", bare.display());
    let (_, free) = run(&["--urdf", &bare_arg], "bare.json");
    assert_eq!(free["success"], Value::Bool(true), "{free}");
    assert!(
        free["iterations"].as_u64().unwrap() < own["iterations"].as_u64().unwrap().max(1),
        "{free}"
    );
    // Refused before any plan, leaving no results file: no `=`, a robot no problem file plans,
    // a robot named twice, a missing file, a model without the problems' joints.
    let missing = dir.join("missing.urdf");
    let missing_arg = format!("panda={}", missing.display());
    let tiny = dir.join("tiny.urdf");
    std::fs::write(&tiny, r#"<robot name="t"><link name="a"/></robot>"#).unwrap();
    let tiny_arg = format!("panda={}", tiny.display());
    for (extra, says) in [
        (vec!["--urdf", "panda"], "expected ROBOT=PATH"),
        (vec!["--urdf", "fetch=x.urdf"], "plans robot `fetch`"),
        (vec!["--urdf", &same_file, "--urdf", &same_file], "twice"),
        (vec!["--urdf", &missing_arg], "missing.urdf"),
        (vec!["--urdf", &tiny_arg], "panda_joint1"),
    ] {
        let refused = dir.join("refused.json");
        let json = ["--json", refused.to_str().unwrap()];
        let err = fails(&[&common[..], &extra[..], &json[..]].concat());
        assert!(err.contains(says), "{extra:?}: {err}");
        assert!(!refused.exists(), "{extra:?} left a results file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bench_plan_writes_results_json() {
    let dir = std::env::temp_dir().join(format!("hearth_cli_plan_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/planning/tests/data/panda_table_pick.json");
    let bench_plan = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_hearth"))
            .args(["bench", "plan", "--problems", data])
            .args(extra)
            .output()
            .unwrap()
    };
    // Runs the command with `extra` and `--json` to a file named `name`: its stderr and JSON.
    let bench_json = |extra: &[&str], name: &str| {
        let path = dir.join(name);
        let o = bench_plan(&[extra, &["--json", path.to_str().unwrap()][..]].concat());
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{extra:?}: {err}");
        let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        (err, v)
    };
    let (_, v) = bench_json(&["--planner", "birrt", "--time-limit", "2"], "plan.json");
    let results = v["results"].as_array().unwrap();
    assert_eq!(results.len(), 2, "one row per problem");
    // Problem 41 is marked invalid in the set: reported as skipped, not failed.
    let p41 = results.iter().find(|r| r["id"] == 41).unwrap();
    assert!(p41["skipped"].as_str().unwrap().contains("invalid"));
    let p1 = results.iter().find(|r| r["id"] == 1).unwrap();
    assert!(p1.get("success").is_some() || p1.get("skipped").is_some(), "{p1}");
    assert!(v["summary"]["table_pick"]["plans"].as_u64() == Some(2));
    // One robot: the families and `all`, with the count of solved and attempted plans.
    let all = &v["summary"]["all"];
    assert_eq!(
        (all["plans"].as_u64(), all["attempted"].as_u64()),
        (Some(2), Some(1)),
        "{all}"
    );
    assert!(results.iter().all(|r| r["robot"] == "panda"), "{results:?}");
    assert!(
        v["summary"]["table_pick"]["smoothing_fell_back"].is_u64(),
        "{}",
        v["summary"]
    );
    // Two robots' problem sets in one run: their families share a name, so the summary keys
    // name the robot; the folder's `joints.json` (the Panda's) is not applied to the Fetch.
    let fetch = concat!(env!("CARGO_MANIFEST_DIR"), "/planning/tests/data/fetch_table_pick.json");
    let (err, v) = bench_json(
        &["--problems", fetch, "--warm-up", "0", "--shortcut", "none"],
        "both.json",
    );
    assert!(err.contains("describes robot `panda`, not used"), "{err}");
    for key in ["panda/table_pick", "fetch/table_pick", "panda/all", "fetch/all"] {
        assert!(v["summary"][key]["plans"].is_u64(), "{key}: {}", v["summary"]);
    }
    assert!(v["summary"].get("table_pick").is_none(), "{}", v["summary"]);
    // One field of every result row.
    let field = |v: &serde_json::Value, key: &str| -> Vec<serde_json::Value> {
        v["results"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r[key].clone())
            .collect()
    };
    assert_eq!(field(&v, "robot"), ["panda", "panda", "fetch"]);
    // LazyPRM takes the benchmark's step and greedy growth for the Fetch, its own defaults for
    // the Panda; `--tree-connect` sets the greedy growth for both. A robot's setup line ends
    // with its planner step. The Panda's first table_pick problem wedges a query end, so its
    // plan shows whether the growth was greedy (in the unweighted joint space: with the
    // joints' reach as weights, the default, no query end of it is wedged).
    let lazy = |tree_connect: Option<&str>, weights: &'static str, name: &str| {
        let mut args = vec![
            "--problems",
            fetch,
            "--planner",
            "lazyprm",
            "--warm-up",
            "0",
            "--shortcut",
            "none",
            "--weights",
            weights,
        ];
        if let Some(value) = tree_connect {
            args.extend(["--tree-connect", value]);
        }
        let (err, v) = bench_json(&args, name);
        let p1 = v["results"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["robot"] == "panda" && r["id"] == 1)
            .unwrap()
            .clone();
        assert_eq!(p1["success"], true, "{p1}");
        (err, p1["checks"].as_u64().unwrap())
    };
    let setup_ends = |err: &str, robot: &str, step: &str| {
        err.lines()
            .any(|l| l.starts_with(&format!("{robot}: ")) && l.ends_with(step))
    };
    let (err, chosen) = lazy(None, "none", "lazy.json");
    assert!(
        setup_ends(&err, "fetch", "LazyPRM step 4 rad, wedged ends grown greedily")
            && setup_ends(&err, "panda", "LazyPRM step the planner's default"),
        "{err}"
    );
    let (err, off) = lazy(Some("false"), "none", "lazy_off.json");
    assert!(
        setup_ends(&err, "fetch", "LazyPRM step 4 rad")
            && setup_ends(&err, "panda", "LazyPRM step the planner's default"),
        "--tree-connect false: {err}"
    );
    let (err, on) = lazy(Some("true"), "none", "lazy_on.json");
    assert!(
        setup_ends(&err, "fetch", "LazyPRM step 4 rad, wedged ends grown greedily")
            && setup_ends(
                &err,
                "panda",
                "LazyPRM step the planner's default, wedged ends grown greedily"
            ),
        "--tree-connect true: {err}"
    );
    assert!(
        chosen == off && on != off,
        "Panda checks: chosen {chosen}, off {off}, on {on}"
    );
    // With the weights (the default), the Fetch's LazyPRM takes the step that goes with them.
    let (err, _) = lazy(None, "reach", "lazy_weighted.json");
    assert!(
        setup_ends(&err, "fetch", "LazyPRM step 2 rad, wedged ends grown greedily")
            && err.contains("(the joints' reach)"),
        "{err}"
    );
    // Two racing copies per plan: said on the setup line; the same seed plans the same paths.
    let raced = |name: &str| {
        let (err, v) = bench_json(
            &[
                "--threads",
                "2",
                "--iterations",
                "20000",
                "--time-limit",
                "100",
                "--emit-paths",
                "--shortcut",
                "none",
            ],
            name,
        );
        assert!(err.contains("2 copies racing per plan"), "{err}");
        v
    };
    let (a, b) = (raced("race_a.json"), raced("race_b.json"));
    assert_eq!(field(&a, "success"), field(&b, "success"));
    assert!(field(&a, "success").contains(&serde_json::json!(true)), "{a}");
    assert_eq!(field(&a, "path"), field(&b, "path"));
    // No time limit at all (an infinite one) plans and smooths as usual.
    let (_, v) = bench_json(
        &["--only", "table_pick:1", "--time-limit", "inf", "--warm-up", "0"],
        "unlimited.json",
    );
    assert_eq!(field(&v, "success"), vec![serde_json::json!(true)], "{v}");
    // `--only` picks one problem; a selector that matches nothing or a malformed id is an error.
    let (_, v) = bench_json(&["--only", "table_pick:41"], "only.json");
    assert_eq!(field(&v, "id"), vec![serde_json::json!(41)]);
    // The Panda's BiRRT takes the planner's connection unless told otherwise; a solved plan
    // reports its trees' sizes.
    for (connect, says) in [
        (&[][..], "BiRRT step 0.5 rad, other connection"),
        (&["--connect", "onward"][..], "BiRRT step 0.5 rad, onward connection"),
    ] {
        let (err, v) = bench_json(&[&["--only", "table_pick:1"][..], connect].concat(), "connect.json");
        assert!(err.contains(says), "{connect:?}: {err}");
        let r = &v["results"][0];
        assert!(
            r["success"] == true && r["tree_sizes"].as_array().is_some_and(|t| t.len() == 2),
            "{r}"
        );
    }
    // BiRRT plans with the joints' reach as distance weights (said on the setup line, the
    // last wrist joint lightest) unless told otherwise, with the step that goes with them;
    // path lengths are reported unweighted either way: no shorter than the straight line
    // from start to goal in radians, which the weighted metric would shorten.
    let problem: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(data).unwrap()).unwrap();
    let p1 = problem["problems"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["id"] == 1)
        .unwrap();
    let straight = p1["start"]
        .as_array()
        .unwrap()
        .iter()
        .zip(p1["goals"][0].as_array().unwrap())
        .map(|(a, b)| (a.as_f64().unwrap() - b.as_f64().unwrap()).powi(2))
        .sum::<f64>()
        .sqrt();
    for (weights, says) in [
        (
            &[][..],
            "distance weights 1.00, 1.00, 0.72, 0.65, 0.30, 0.30, 0.23 (the joints' reach); BiRRT step 0.5 rad",
        ),
        (&["--weights", "reach"][..], "(the joints' reach); BiRRT step 0.5 rad"),
        (&["--weights", "none"][..], "joints.json; BiRRT step 0.65 rad"),
    ] {
        let (err, v) = bench_json(&[&["--only", "table_pick:1"][..], weights].concat(), "weights.json");
        assert!(err.contains(says), "{weights:?}: {err}");
        let length = v["results"][0]["path_length"].as_f64().unwrap();
        assert!(length >= straight - 1e-9, "{weights:?}: length {length} < {straight}");
    }
    let err = fails(&["bench", "plan", "--problems", data, "--weights", "heavy"]);
    assert!(err.contains("--weights"), "{err}");
    // A weight schedule (BiRRT, the reach weights, one thread) is named on the setup line and
    // plans; with another planner, without the weights or with racing copies it is refused,
    // as is a malformed one.
    let (err, v) = bench_json(
        &["--only", "table_pick:1", "--weight-schedule", "2,0.5@50"],
        "schedule.json",
    );
    assert!(
        err.contains("BiRRT step 0.5 rad, other connection, the reach weights to the power 2, 0.5 from iteration 50"),
        "{err}"
    );
    assert_eq!(v["results"][0]["success"], true, "{v}");
    // The JSON file keeps the setup line.
    let line = v["setup"]["panda"].as_str().unwrap_or_default();
    assert!(line.contains("0.5 from iteration 50") && err.contains(line), "{line}");
    for (extra, says) in [
        (&["--planner", "rrt"][..], "--planner birrt only"),
        (&["--weights", "none"][..], "--weights none"),
        (&["--threads", "2"][..], "one thread"),
        (&[][..], "between 0 and 4"),
    ] {
        let schedule = if extra.is_empty() { "2,9@50" } else { "2" };
        let args = [
            &["bench", "plan", "--problems", data, "--weight-schedule", schedule][..],
            extra,
        ]
        .concat();
        let err = fails(&args);
        assert!(err.contains(says), "{args:?}: {err}");
    }
    // An iteration limit ends a plan that the time limit would not: the same plan on any
    // machine, stopped at the same iteration (or solved within it).
    let (_, v) = bench_json(
        &[
            "--only",
            "table_pick:1",
            "--iterations",
            "3",
            "--time-limit",
            "60",
            "--warm-up",
            "0",
        ],
        "iterations.json",
    );
    let r = &v["results"][0];
    // A stopped plan reports its statistics in the same fields as a solved one.
    let stopped = r["error"].as_str().is_some_and(|e| e.contains("(3 iterations"))
        && r["iterations"] == 3
        && r["plan_time_s"].as_f64().is_some_and(|t| t >= 0.0)
        && r["tree_sizes"].as_array().is_some_and(|t| t.len() == 2);
    let within = r["success"] == true && r["iterations"].as_u64().is_some_and(|n| n <= 3);
    assert!(stopped || within, "{r}");
    // RRT on the Panda takes the benchmark's settings for it unless told otherwise; LazyPRM
    // takes the pocket escape's flags.
    for (extra, says) in [
        (&["--planner", "rrt"][..], "RRT step 6 rad, goal zone 0.8"),
        (
            &["--planner", "rrt", "--range", "2", "--goal-zone", "0"][..],
            "RRT step 2 rad, goal zone 0",
        ),
        (&["--planner", "lazyprm", "--no-escape"][..], "LazyPRM step"),
    ] {
        let common = ["--only", "table_pick:1", "--warm-up", "0", "--shortcut", "none"];
        let o = bench_plan(&[&common[..], extra].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success() && err.contains(says), "{extra:?}: {err}");
    }
    for (extra, says) in [
        (&["--only", "table_pick:7"][..], "no such problem"),
        (&["--only", "bookshelf"][..], "no such problem"),
        (&["--only", "table_pick:x"][..], "not a problem id"),
        (&["--dynamic-domain", "0"][..], "--dynamic-domain must be positive"),
        (&["--dynamic-domain", "2", "--planner", "rrt"][..], "birrt only"),
        (
            &["--goal-zone", "0.99", "--planner", "rrt"][..],
            "--goal-zone must be in [0, 0.95]",
        ),
        (
            &["--no-escape", "--planner", "rrt"][..],
            "apply to --planner birrt and lazyprm only",
        ),
        (&["--escape-probe", "1"][..], "--escape-probe must be in [0, 1)"),
        (&["--iterations", "0"][..], "--iterations must be positive"),
        (&["--threads", "0"][..], "0 is not in 1..=256"),
        (&["--time-limit", "0"][..], "--time-limit must be positive"),
        (
            &["--resolution", "inf"][..],
            "--resolution and --fine-resolution must be positive and finite",
        ),
        (
            &["--fine-resolution", "0"][..],
            "--resolution and --fine-resolution must be positive and finite",
        ),
        // A spacing that would cut an edge into ~10³⁰⁰ states (it used to run out of memory).
        (
            &["--resolution", "1e-300"][..],
            "is finer than the panda planning space allows",
        ),
        (
            &["--fine-resolution", "1e-9"][..],
            "is finer than the panda planning space allows",
        ),
        (
            &["--range", "1e-9"][..],
            "is finer than the panda planning space allows",
        ),
        (&["--escape-share", "0"][..], "--escape-share must be in (0, 1)"),
        (
            &["--no-escape", "--escape-probe", "0.5"][..],
            "set the escape that --no-escape turns off",
        ),
        (
            &["--no-escape", "--escape-reset", "5"][..],
            "set the escape that --no-escape turns off",
        ),
        (
            &["--planner", "rrt", "--escape-reset", "5"][..],
            "apply to --planner birrt and lazyprm only",
        ),
        (
            &["--connect", "onward", "--planner", "rrt"][..],
            "--connect applies to --planner birrt only",
        ),
        (&["--connect", "sideways"][..], "invalid value 'sideways'"),
        (
            &["--tree-connect", "true"][..],
            "--tree-connect applies to --planner lazyprm only",
        ),
        (
            &["--planner", "lazyprm", "--tree-connect", "yes"][..],
            "invalid value 'yes'",
        ),
        (&["--repeat", "0"][..], "0 is not in 1.."),
    ] {
        let o = bench_plan(extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            !o.status.success() && err.contains(says) && !err.contains("panicked"),
            "{extra:?}: {err}"
        );
    }
    // A start outside the joint limits is skipped for that reason, whatever its links touch.
    let mut far: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(data).unwrap()).unwrap();
    let p1 = far["problems"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|p| p["id"] == 1)
        .unwrap();
    // (Every joint at 1e308 rad puts link 1 against link 5.)
    p1["start"] = serde_json::json!(vec![1e308; 7]);
    let far_path = dir.join("far_start.json");
    std::fs::write(&far_path, far.to_string()).unwrap();
    let (_, v) = bench_json(
        &[
            "--problems",
            far_path.to_str().unwrap(),
            "--warm-up",
            "0",
            "--shortcut",
            "none",
        ],
        "far.json",
    );
    let skipped = field(&v, "skipped");
    // The reason names the value as 1e308, not as 309 digits.
    assert!(
        skipped.iter().any(|s| s
            .as_str()
            .is_some_and(|s| s.contains("outside our model's limits: start")
                && s.contains("is 1e308")
                && s.len() < 200)),
        "{skipped:?}"
    );
    // A results file that cannot be written fails the run before its first plan.
    let unwritable = bench_plan(&["--json", "/nonexistent/dir/results.json"]);
    let err = String::from_utf8_lossy(&unwritable.stderr);
    assert!(
        !unwritable.status.success() && err.contains("writing /nonexistent/dir/results.json"),
        "{err}"
    );
    assert!(!err.contains("plans") && !err.contains("panicked"), "{err}");
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_hearth"))
        .args(["bench", "plan", "--problems", "/nonexistent/problems.json"])
        .output()
        .unwrap();
    assert!(!bad.status.success());
    assert!(!String::from_utf8_lossy(&bad.stderr).contains("panicked"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `bench sim` on a small generated home with the Fetch: a few steps, quickly.
const SMALL_SIM: [&str; 15] = [
    "bench",
    "sim",
    "--generate",
    "1",
    "--rooms",
    "2",
    "--robot",
    "fetch",
    "--steps",
    "8",
    "--chunks",
    "2",
    "--settle",
    "5",
    "--no-sleep",
];

#[test]
fn bench_sim_writes_json() {
    let dir = temp_dir("bench_sim");
    let path = dir.join("sim.json");
    let args = [&SMALL_SIM[..], &["--json", path.to_str().unwrap()][..]].concat();
    let o = hearth(&args);
    assert!(o.status.success(), "bench sim failed: {}", stderr(&o));
    let text = std::fs::read_to_string(&path).expect("bench sim wrote its JSON file");
    let report: Value = serde_json::from_str(&text).unwrap_or_else(|e| panic!("not JSON ({e}): {text}"));
    for key in ["physics_hz_median", "physics_hz_median_without_robot"] {
        let hz = report[key]
            .as_f64()
            .unwrap_or_else(|| panic!("`{key}` missing: {report}"));
        assert!(hz.is_finite() && hz > 0.0, "{key} = {hz}");
    }
    assert_eq!(report["robot"], "fetch");
    assert_eq!(report["sleeping"], false);
    let bodies = report["bodies"].as_u64().expect("bodies");
    assert!(bodies > report["bodies_without_robot"].as_u64().unwrap(), "{report}");
    // The same run gives the same final state.
    let hash = report["state_hash"].as_str().expect("state_hash").to_owned();
    assert!(hearth(&args).status.success());
    let again: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(again["state_hash"].as_str(), Some(hash.as_str()));
    // Neither a scene nor a seed: a clean error.
    fails(&["bench", "sim", "--robot", "none"]);
    let err = fails(&["bench", "sim", "--scene", "/nonexistent/home.json"]);
    assert!(err.contains("/nonexistent/home.json"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn dataset_pushes_writes_locations_and_resumes() {
    let dir = std::env::temp_dir().join(format!("hearth-cli-pushes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.to_str().unwrap();
    let args = [
        "dataset",
        "pushes",
        "--generate",
        "1",
        "--rooms",
        "2",
        "--locations",
        "1",
        "--pushes-per-location",
        "2",
        "--kinematic",
        "--backend",
        "raycast",
        "--size",
        "32",
        "--out",
        out,
    ];
    let o = hearth(&args);
    assert!(o.status.success(), "dataset pushes failed: {}", stderr(&o));
    assert!(
        stdout(&o).contains("1 locations written") && stdout(&o).contains("pushes/s"),
        "{}",
        stdout(&o)
    );
    for f in ["rgb.png", "mask.npy", "mask_rgb.png", "pushes.json"] {
        assert!(dir.join("loc_00000").join(f).is_file(), "{f}");
    }
    let again = hearth(&args);
    assert!(
        stdout(&again).contains("0 locations written, 1 skipped"),
        "{}",
        stdout(&again)
    );
    let err = fails(&["dataset", "pushes", "--generate", "1", "--locations", "0", "--out", out]);
    assert!(err.contains("locations"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn demo_runs_the_story_and_writes_the_success_rate() {
    let dir = temp_dir("demo");
    let path = dir.join("demo.json");
    let o = hearth(&["demo", "--seeds", "1", "--kinematic", "--json", path.to_str().unwrap()]);
    assert!(o.status.success(), "demo failed: {}", stderr(&o));
    assert!(stdout(&o).contains("success rate"), "{}", stdout(&o));
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let runs = report["runs"].as_array().expect("runs");
    assert_eq!(runs.len(), 1);
    assert_eq!(runs[0]["seed"], 3);
    assert_eq!(runs[0]["success"], true, "{report}");
    assert_eq!(report["success_rate"], 1.0);
    // A single run writes its images, report and trajectory.
    let out = dir.join("one");
    let o = hearth(&["demo", "--kinematic", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "demo failed: {}", stderr(&o));
    assert!(stdout(&o).contains("place_in_sink"), "{}", stdout(&o));
    let trajectory: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("trajectory.json")).unwrap()).unwrap();
    assert!(trajectory["samples"].as_array().is_some_and(|s| s.len() >= 6));
    assert!(out.join("report.json").exists());
    // Bad arguments are clean errors.
    let err = fails(&["demo", "--rooms", "40"]);
    assert!(err.contains("--rooms"), "{err}");
    fails(&["demo", "--seeds", "0"]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every benchmark reports a `--json` file it cannot write before it measures anything.
#[test]
fn benches_refuse_an_unwritable_json_file_before_measuring() {
    let bad = "/nonexistent/dir/bench.json";
    for (args, measured) in [
        (
            &["bench", "kin", "--robot", "panda", "--samples", "5"][..],
            "FK, all links",
        ),
        (&SMALL_SIM[..], "Hz median"),
        (
            &[
                "bench",
                "lidar",
                "--generate",
                "1",
                "--rooms",
                "2",
                "--scans",
                "10",
                "--chunks",
                "1",
            ][..],
            "scans/s",
        ),
        (
            &[
                "bench",
                "render",
                "--generate",
                "1",
                "--rooms",
                "2",
                "--backend",
                "raycast",
                "--frames",
                "1",
                "--modalities",
                "depth",
            ][..],
            "depth",
        ),
        (
            &[
                "bench",
                "env",
                "--config",
                "examples/configs/point_nav_random.toml",
                "--envs",
                "1",
                "--steps",
                "2",
            ][..],
            "steps/s",
        ),
    ] {
        let o = hearth(&[args, &["--json", bad][..]].concat());
        let (out, err) = (stdout(&o), stderr(&o));
        assert!(
            !o.status.success() && err.contains(&format!("writing {bad}")),
            "{args:?}: {err}"
        );
        assert!(
            !err.contains("panicked") && !out.contains(measured),
            "{args:?} measured first:\n{out}"
        );
    }
}

/// `bench compare` matches two `bench plan` runs plan by plan: a run against a rerun with the
/// same seed is the same in every plan; files that are not results are refused by name.
#[test]
fn bench_compare_matches_two_runs_plan_by_plan() {
    let dir = temp_dir("compare");
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/planning/tests/data/panda_table_pick.json");
    let run = |seed: &str, name: &str| {
        let path = dir.join(name);
        let args = [
            "bench",
            "plan",
            "--problems",
            data,
            "--planner",
            "birrt",
            "--shortcut",
            "none",
            "--warm-up",
            "0",
            "--seed",
            seed,
            "--json",
            path.to_str().unwrap(),
        ];
        let o = hearth(&args);
        assert!(o.status.success(), "bench plan failed: {}", stderr(&o));
        path.to_str().unwrap().to_owned()
    };
    let (a, b, c) = (run("3", "a.json"), run("3", "b.json"), run("4", "c.json"));
    let out = dir.join("compare.json");
    let o = hearth(&["bench", "compare", &a, &b, "--json", out.to_str().unwrap()]);
    assert!(o.status.success(), "bench compare failed: {}", stderr(&o));
    assert!(stdout(&o).contains("table_pick"), "{}", stdout(&o));
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let all = &v["groups"]["all"];
    // Problem 41 is skipped in both runs; problem 1 is planned in both, the same plan.
    assert_eq!(
        (all["plans"].as_u64(), all["same_plans"].as_u64()),
        (Some(1), Some(1)),
        "{v}"
    );
    assert_eq!(all["solved_both"].as_u64(), Some(1), "{v}");
    assert!(all["median_ratio"].as_f64().is_some_and(|r| r > 0.0), "{v}");
    // Another seed plans the same problem another way.
    let o = hearth(&["bench", "compare", &a, &c]);
    assert!(o.status.success(), "bench compare failed: {}", stderr(&o));
    let row = stdout(&o)
        .lines()
        .find(|l| l.starts_with("all"))
        .unwrap_or_default()
        .to_owned();
    assert!(row.split_whitespace().last() == Some("0"), "not the same plan: {row}");
    // A problem file is not a results file; a missing file is named.
    let err = fails(&["bench", "compare", data, &a]);
    assert!(err.contains("has no `results` list"), "{err}");
    let missing = dir.join("missing.json");
    let err = fails(&["bench", "compare", &a, missing.to_str().unwrap()]);
    assert!(err.contains("cannot read") && err.contains("missing.json"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
