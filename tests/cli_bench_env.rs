//! `hearth bench env` end to end on a small config: it reports its rates and the camera
//! backend `auto` resolved to (the CPU rasteriser for a depth-only camera), and refuses zero
//! steps with a message.

use std::process::Command;

use serde_json::Value;

const CONFIG: &str = r#"
[scene]
generate = 1
rooms = 2
small_objects = false

[task]
name = "point_nav_random"

[sensors]
modalities = ["task_obs", "scan", "depth"]

[sensors.camera]
width = 32
height = 24

[episode]
max_steps = 20
"#;

#[test]
fn bench_env_reports_rates_and_the_camera_backend() {
    let dir = std::env::temp_dir().join(format!("hearth-bench-env-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("env.toml");
    std::fs::write(&config, CONFIG).unwrap();
    let json = dir.join("env.json");
    let run = |steps: &str| {
        Command::new(env!("CARGO_BIN_EXE_hearth"))
            .args(["bench", "env", "--config", config.to_str().unwrap(), "--envs", "2"])
            .args(["--steps", steps, "--json", json.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let o = run("5");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("camera: raster"));
    let report: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["camera_backend"], "raster", "{report}");
    for key in ["steps_per_s_single", "steps_per_s_vec"] {
        let v = report[key].as_f64().unwrap_or_else(|| panic!("{key}: {report}"));
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    let o = run("0");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--steps"));
    let _ = std::fs::remove_dir_all(&dir);
}
