//! `hearth bench compare`: two `hearth bench plan --json` files side by side, plan by plan.
//!
//! Comparing two builds, two settings or two seeds on the same problems is most of planner
//! benchmarking. Medians taken over each run's own solved plans mix two things: a run that
//! solves more hard problems has a higher median. So the comparison matches the plans of the
//! two files (robot, family, problem id and repeat) and takes its times over the plans both
//! runs solved; it also counts the plans that are the same plan in both (same success, checks,
//! iterations and path length), which tells a change that alters no plan from one that does.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use serde_json::{Value, json};

use super::bench::{create_json, percentile};

#[derive(Args, Debug)]
pub struct BenchCompareArgs {
    /// The reference run: a file written by `hearth bench plan --json`.
    base: PathBuf,
    /// The run compared with it, on the same problems.
    new: PathBuf,
    /// Also write the comparison as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// One plan of a results file, as the comparison needs it.
#[derive(Clone, Debug, PartialEq)]
struct Plan {
    /// Whether the plan was attempted (not skipped).
    attempted: bool,
    success: bool,
    /// Planning time of a solved plan, in milliseconds.
    time_ms: Option<f64>,
    /// What makes two runs' plans the same plan: success, states checked while planning,
    /// iterations and path length, as written.
    signature: [Value; 4],
}

/// Where a plan sits: robot, family, problem id, repeat.
type Key = (String, String, u64, u64);

/// The plans of one results file, keyed by robot, family, id and repeat.
fn plans(v: &Value, path: &Path) -> anyhow::Result<BTreeMap<Key, Plan>> {
    let Some(rows) = v.get("results").and_then(Value::as_array) else {
        bail!(
            "{} has no `results` list: not a file written by `hearth bench plan --json`",
            path.display()
        );
    };
    let mut out = BTreeMap::new();
    for (i, row) in rows.iter().enumerate() {
        let text = |key: &str| -> anyhow::Result<String> {
            row.get(key)
                .and_then(Value::as_str)
                .map(str::to_owned)
                .with_context(|| format!("{}: result {i} has no `{key}` text", path.display()))
        };
        let (robot, family) = (text("robot")?, text("family")?);
        let id = row
            .get("id")
            .and_then(Value::as_u64)
            .with_context(|| format!("{}: result {i} has no numeric `id`", path.display()))?;
        let repeat = match row.get("repeat") {
            None => 0,
            Some(r) => r
                .as_u64()
                .with_context(|| format!("{}: result {i} has `repeat` {r}, not a count", path.display()))?,
        };
        let attempted = row.get("skipped").is_none();
        let success = row.get("success") == Some(&Value::Bool(true));
        let time_ms = match row.get("plan_time_s") {
            None | Some(Value::Null) => None,
            Some(t) => match t.as_f64() {
                Some(s) if s.is_finite() && s >= 0.0 => Some(s * 1e3),
                _ => bail!(
                    "{}: result {i} ({family} {id}) has `plan_time_s` {t}, not a time",
                    path.display()
                ),
            },
        };
        if success && time_ms.is_none() {
            bail!(
                "{}: result {i} ({family} {id}) is solved but has no `plan_time_s`",
                path.display()
            );
        }
        let field = |key: &str| row.get(key).cloned().unwrap_or(Value::Null);
        let signature = [
            Value::Bool(success),
            field("plan_checks"),
            field("iterations"),
            field("path_length"),
        ];
        let key = (robot, family, id, repeat);
        let plan = Plan {
            attempted,
            success,
            time_ms,
            signature,
        };
        if out.insert(key.clone(), plan).is_some() {
            bail!(
                "{}: plan {}/{} {} (repeat {}) appears twice",
                path.display(),
                key.0,
                key.1,
                key.2,
                key.3
            );
        }
    }
    Ok(out)
}

/// The comparison of one group of plans (a family, or all).
#[derive(Debug, Default)]
struct Group {
    /// Plans attempted in both runs.
    plans: usize,
    solved_base: usize,
    solved_new: usize,
    /// Planning times (ms) of the plans both runs solved: base, new.
    both: Vec<(f64, f64)>,
    /// Plans that are the same plan in both runs.
    same: usize,
}

impl Group {
    fn add(&mut self, a: &Plan, b: &Plan) {
        self.plans += 1;
        self.solved_base += usize::from(a.success);
        self.solved_new += usize::from(b.success);
        if let (true, true, Some(ta), Some(tb)) = (a.success, b.success, a.time_ms, b.time_ms) {
            self.both.push((ta, tb));
        }
        self.same += usize::from(a.signature == b.signature);
    }

    /// Median planning times over the plans both solved (base, new), the ratio of the
    /// medians (new over base), and the geometric mean of the plans' own ratios. A plan
    /// timed at zero (a start that is already a goal) has no ratio of its own and is left
    /// out of the geometric mean.
    fn times(&self) -> (f64, f64, f64, f64) {
        let base: Vec<f64> = self.both.iter().map(|p| p.0).collect();
        let new: Vec<f64> = self.both.iter().map(|p| p.1).collect();
        let (mb, mn) = (percentile(&base, 0.5), percentile(&new, 0.5));
        let logs: Vec<f64> = self
            .both
            .iter()
            .filter(|(b, n)| *b > 0.0 && *n > 0.0)
            .map(|(b, n)| (n / b).ln())
            .collect();
        let gmean = if logs.is_empty() {
            f64::NAN
        } else {
            (logs.iter().sum::<f64>() / logs.len() as f64).exp()
        };
        (mb, mn, mn / mb, gmean)
    }

    fn to_json(&self) -> Value {
        let (mb, mn, ratio, gmean) = self.times();
        let num = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
        // Of the plans both solved, those the new run planned in less time: with the
        // ratios, a first sign of whether a change helps most plans or a few.
        let faster = self.both.iter().filter(|(b, n)| n < b).count();
        json!({"plans": self.plans, "solved_base": self.solved_base, "solved_new": self.solved_new,
               "solved_both": self.both.len(), "new_faster": faster, "same_plans": self.same,
               "plan_time_ms_median_base": num(mb), "plan_time_ms_median_new": num(mn),
               "median_ratio": num(ratio), "geometric_mean_ratio": num(gmean)})
    }
}

/// The comparison of two parsed results files: one group per family (`robot/family` when the
/// plans cover several robots) and `all`, and the counts of plans not attempted in both.
fn compare(base: &Value, new: &Value, paths: [&Path; 2]) -> anyhow::Result<Value> {
    let (a, b) = (plans(base, paths[0])?, plans(new, paths[1])?);
    let robots: std::collections::BTreeSet<&str> = a.keys().map(|k| k.0.as_str()).collect();
    let mut groups: BTreeMap<String, Group> = BTreeMap::new();
    let mut all = Group::default();
    let (mut only_base, mut skipped_in_one) = (0usize, 0usize);
    for (key, pa) in &a {
        let Some(pb) = b.get(key) else {
            only_base += 1;
            continue;
        };
        if !(pa.attempted && pb.attempted) {
            skipped_in_one += usize::from(pa.attempted || pb.attempted);
            continue;
        }
        let name = if robots.len() > 1 {
            format!("{}/{}", key.0, key.1)
        } else {
            key.1.clone()
        };
        groups.entry(name).or_default().add(pa, pb);
        all.add(pa, pb);
    }
    let only_new = b.keys().filter(|k| !a.contains_key(*k)).count();
    if all.plans == 0 {
        bail!(
            "no plan was attempted in both {} and {}: compare runs of the same problems",
            paths[0].display(),
            paths[1].display()
        );
    }
    let mut out = serde_json::Map::new();
    for (name, g) in groups.iter().chain(std::iter::once((&"all".to_owned(), &all))) {
        out.insert(name.clone(), g.to_json());
    }
    Ok(
        json!({"base": paths[0].display().to_string(), "new": paths[1].display().to_string(),
              "groups": out,
              "unmatched": {"only_in_base": only_base, "only_in_new": only_new,
                            "skipped_in_one": skipped_in_one}}),
    )
}

fn read(path: &Path) -> anyhow::Result<Value> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not JSON", path.display()))
}

/// One row of the comparison table, the header included: the family column left-aligned, the
/// figures right-aligned under their headings.
fn print_row(cells: [&str; 11]) {
    let [
        family,
        plans,
        solved_base,
        solved_new,
        both,
        base_ms,
        new_ms,
        ratio,
        geo,
        faster,
        same,
    ] = cells;
    println!(
        "{family:<22} {plans:>6} {solved_base:>11} {solved_new:>10} {both:>6} {base_ms:>10} {new_ms:>10} \
         {ratio:>9} {geo:>9} {faster:>7} {same:>6}"
    );
}

pub fn run(a: BenchCompareArgs) -> anyhow::Result<()> {
    let (base, new) = (read(&a.base)?, read(&a.new)?);
    let out = compare(&base, &new, [&a.base, &a.new])?;
    create_json(a.json.as_deref())?;
    println!("base: {}\nnew:  {}", a.base.display(), a.new.display());
    print_row([
        "family",
        "plans",
        "solved base",
        "solved new",
        "both",
        "base ms",
        "new ms",
        "new/base",
        "geo mean",
        "faster",
        "same",
    ]);
    let cell = |v: &Value, digits: usize| v.as_f64().map_or("-".to_owned(), |x| format!("{x:.digits$}"));
    let count = |v: &Value| v.as_u64().map_or("-".to_owned(), |n| n.to_string());
    // Families first, then `all`, as `hearth bench plan` prints them.
    let groups = out["groups"].as_object().into_iter().flatten();
    let (all, families): (Vec<_>, Vec<_>) = groups.partition(|(name, _)| name.as_str() == "all");
    for (name, g) in families.into_iter().chain(all) {
        print_row([
            name.as_str(),
            &count(&g["plans"]),
            &count(&g["solved_base"]),
            &count(&g["solved_new"]),
            &count(&g["solved_both"]),
            &cell(&g["plan_time_ms_median_base"], 3),
            &cell(&g["plan_time_ms_median_new"], 3),
            &cell(&g["median_ratio"], 3),
            &cell(&g["geometric_mean_ratio"], 3),
            &count(&g["new_faster"]),
            &count(&g["same_plans"]),
        ]);
    }
    let u = &out["unmatched"];
    let unmatched: u64 = ["only_in_base", "only_in_new", "skipped_in_one"]
        .iter()
        .filter_map(|k| u[*k].as_u64())
        .sum();
    if unmatched > 0 {
        println!(
            "not compared: {} plans only in the base run, {} only in the new run, {} skipped in one run",
            u["only_in_base"], u["only_in_new"], u["skipped_in_one"]
        );
    }
    println!(
        "times are medians over the plans both runs solved; new/base below 1 means the new run planned faster; \
         faster: the plans both solved that the new run planned in less time"
    );
    if let Some(path) = &a.json {
        std::fs::write(path, serde_json::to_string(&out)?).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(family: &str, id: u64, success: bool, time_s: f64, checks: u64) -> Value {
        json!({"robot": "panda", "family": family, "id": id, "planner": "birrt", "repeat": 0,
               "success": success, "plan_time_s": time_s, "plan_checks": checks,
               "iterations": checks / 3, "path_length": 1.5})
    }

    fn file(rows: Vec<Value>) -> Value {
        json!({"results": rows, "summary": {}})
    }

    const PATHS: [&str; 2] = ["base.json", "new.json"];

    fn run(base: Vec<Value>, new: Vec<Value>) -> anyhow::Result<Value> {
        compare(&file(base), &file(new), PATHS.map(Path::new))
    }

    #[test]
    fn times_are_taken_over_the_plans_both_solve() {
        let base = vec![
            row("box", 1, true, 0.002, 90),
            row("box", 2, true, 0.004, 120),
            row("box", 3, false, 1.0, 9000),
        ];
        let new = vec![
            row("box", 1, true, 0.001, 60),
            row("box", 2, true, 0.004, 120),
            row("box", 3, true, 0.5, 4000),
        ];
        let out = run(base, new).unwrap();
        let g = &out["groups"]["box"];
        assert_eq!((g["plans"].as_u64(), g["solved_both"].as_u64()), (Some(3), Some(2)));
        assert_eq!(
            (g["solved_base"].as_u64(), g["solved_new"].as_u64()),
            (Some(2), Some(3))
        );
        assert_eq!(g["same_plans"].as_u64(), Some(1), "only plan 2 is the same plan");
        assert_eq!(g["new_faster"].as_u64(), Some(1), "plan 1 is faster, plan 2 as fast");
        // Plans 1 and 2: ratios 0.5 and 1, geometric mean √0.5; plan 3 (new only) is left out.
        let gmean = g["geometric_mean_ratio"].as_f64().unwrap();
        assert!((gmean - 0.5f64.sqrt()).abs() < 1e-12, "{gmean}");
        assert_eq!(out["groups"]["all"]["plans"].as_u64(), Some(3));
    }

    #[test]
    fn a_run_against_itself_is_the_same_in_every_plan() {
        let rows = vec![row("box", 1, true, 0.002, 90), row("cage", 4, false, 1.0, 9000)];
        let out = run(rows.clone(), rows).unwrap();
        let all = &out["groups"]["all"];
        assert_eq!(all["same_plans"], all["plans"]);
        assert_eq!(all["median_ratio"].as_f64(), Some(1.0));
        assert_eq!(all["geometric_mean_ratio"].as_f64(), Some(1.0));
    }

    #[test]
    fn unmatched_and_skipped_plans_are_counted_not_compared() {
        let mut skipped = row("box", 2, false, 0.0, 0);
        skipped["skipped"] = json!("start collides");
        let base = vec![row("box", 1, true, 0.002, 90), skipped, row("box", 5, true, 0.002, 90)];
        let new = vec![
            row("box", 1, true, 0.002, 90),
            row("box", 2, true, 0.002, 90),
            row("box", 7, true, 0.002, 90),
        ];
        let out = run(base, new).unwrap();
        assert_eq!(out["groups"]["all"]["plans"].as_u64(), Some(1));
        let u = &out["unmatched"];
        assert_eq!(
            (
                u["only_in_base"].as_u64(),
                u["only_in_new"].as_u64(),
                u["skipped_in_one"].as_u64()
            ),
            (Some(1), Some(1), Some(1))
        );
    }

    #[test]
    fn bad_files_are_refused_with_the_reason() {
        let err = |base: Value, new: Value| compare(&base, &new, PATHS.map(Path::new)).unwrap_err().to_string();
        let good = file(vec![row("box", 1, true, 0.002, 90)]);
        assert!(err(json!({"problems": []}), good.clone()).contains("base.json has no `results` list"));
        let twice = file(vec![row("box", 1, true, 0.002, 90), row("box", 1, true, 0.003, 90)]);
        assert!(err(good.clone(), twice).contains("new.json: plan panda/box 1 (repeat 0) appears twice"));
        let mut no_family = row("box", 1, true, 0.002, 90);
        no_family.as_object_mut().unwrap().remove("family");
        assert!(err(file(vec![no_family]), good.clone()).contains("result 0 has no `family` text"));
        let mut no_time = row("box", 1, true, 0.002, 90);
        no_time.as_object_mut().unwrap().remove("plan_time_s");
        assert!(err(good.clone(), file(vec![no_time])).contains("solved but has no `plan_time_s`"));
        let mut bad_repeat = row("box", 1, true, 0.002, 90);
        bad_repeat["repeat"] = json!("first");
        assert!(err(file(vec![bad_repeat]), good.clone()).contains("has `repeat` \"first\", not a count"));
        let negative = file(vec![row("box", 1, true, -1.0, 90)]);
        assert!(err(good.clone(), negative).contains("not a time"));
        let other = file(vec![row("cage", 1, true, 0.002, 90)]);
        assert!(err(good, other).contains("no plan was attempted in both"));
    }

    /// Any JSON value in place of a row's fields: a comparison, or an error, never a panic;
    /// an accepted comparison's counts add up.
    mod fuzz {
        use super::*;
        use proptest::prelude::*;

        fn any_value() -> impl Strategy<Value = Value> {
            prop_oneof![
                Just(Value::Null),
                any::<bool>().prop_map(Value::Bool),
                any::<i64>().prop_map(|n| json!(n)),
                any::<f64>().prop_map(|x| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)),
                "[a-z_/]{0,8}".prop_map(Value::String),
                Just(json!([])),
                Just(json!({})),
            ]
        }

        const FIELDS: [&str; 9] = [
            "robot",
            "family",
            "id",
            "repeat",
            "skipped",
            "success",
            "plan_time_s",
            "plan_checks",
            "path_length",
        ];

        /// Rows that start valid and have some fields replaced or removed.
        fn rows() -> impl Strategy<Value = Vec<Value>> {
            let edit = (0..FIELDS.len(), proptest::option::of(any_value()));
            // One row in ten is edited, so that both accepted and refused files are common.
            proptest::collection::vec(
                (any::<bool>(), 0.0..1.0f64, proptest::option::weighted(0.1, edit)),
                0..8,
            )
            .prop_map(|specs| {
                specs
                    .into_iter()
                    .zip(0u64..)
                    .map(|((success, t, edit), id)| {
                        let mut r = row("box", id, success, t, 30);
                        if let Some((field, value)) = edit {
                            let o = r.as_object_mut().unwrap();
                            match value {
                                Some(v) => o.insert(FIELDS[field].to_owned(), v),
                                None => o.remove(FIELDS[field]),
                            };
                        }
                        r
                    })
                    .collect()
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(2000))]
            #[test]
            fn never_panics_and_counts_add_up(base in rows(), new in rows()) {
                if let Ok(out) = run(base, new) {
                    let all = &out["groups"]["all"];
                    let n = |k: &str| all[k].as_u64().unwrap();
                    prop_assert!(n("plans") > 0);
                    prop_assert!(n("solved_both") <= n("solved_base").min(n("solved_new")));
                    prop_assert!(n("solved_base") <= n("plans") && n("same_plans") <= n("plans"));
                    prop_assert!(n("new_faster") <= n("solved_both"));
                    let sum: u64 = out["groups"].as_object().unwrap().iter()
                        .filter(|(k, _)| k.as_str() != "all")
                        .map(|(_, g)| g["plans"].as_u64().unwrap())
                        .sum();
                    prop_assert_eq!(sum, n("plans"));
                }
            }
        }
    }

    #[test]
    fn several_robots_are_grouped_by_robot_and_family() {
        let mut fetch = row("box", 1, true, 0.003, 90);
        fetch["robot"] = json!("fetch");
        let rows = vec![row("box", 1, true, 0.002, 90), fetch];
        let out = run(rows.clone(), rows).unwrap();
        let groups = out["groups"].as_object().unwrap();
        let mut names: Vec<&str> = groups.keys().map(String::as_str).collect();
        names.sort_unstable();
        assert_eq!(names, ["all", "fetch/box", "panda/box"]);
    }
}
