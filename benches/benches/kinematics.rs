//! Criterion benches for the kinematics hot path: FK of all links, the Jacobian, and IK.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use hearth_kinematics::{Chain, IkSettings, IkSolver, IkTarget, RobotModel};
use nalgebra::{Matrix6xX, Vector3};
use rand::SeedableRng;

fn configs(m: &RobotModel, n: usize) -> Vec<Vec<f64>> {
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(1);
    (0..n)
        .map(|_| {
            let mut q = vec![0.0; m.dof()];
            m.random_configuration(&mut rng, &mut q);
            q
        })
        .collect()
}

fn fk(c: &mut Criterion) {
    for robot in ["panda", "fetch"] {
        let m = RobotModel::builtin(robot).unwrap();
        let qs = configs(&m, 256);
        let mut poses = m.pose_buffer();
        let mut k = 0;
        c.bench_function(&format!("fk_all_links/{robot}"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                m.fk(black_box(&qs[k]), &mut poses).unwrap();
                black_box(&poses);
            })
        });
    }
}

fn jacobian(c: &mut Criterion) {
    for (robot, chain) in [("panda", "arm"), ("fetch", "arm_with_torso")] {
        let m = RobotModel::builtin(robot).unwrap();
        let chain = Chain::named(&m, chain).unwrap();
        let tip = chain.tip().unwrap();
        let mut poses = m.pose_buffer();
        m.fk(&configs(&m, 1)[0], &mut poses).unwrap();
        let mut j = Matrix6xX::zeros(chain.dof());
        c.bench_function(&format!("jacobian/{robot}"), |b| {
            b.iter(|| {
                m.jacobian(black_box(&poses), &chain, tip, &Vector3::zeros(), &mut j)
                    .unwrap();
                black_box(&j);
            })
        });
    }
}

fn ik(c: &mut Criterion) {
    for (robot, chain) in [("panda", "arm"), ("fetch", "arm_with_torso")] {
        let m = RobotModel::builtin(robot).unwrap();
        let chain = Chain::named(&m, chain).unwrap();
        let tip = m.links()[chain.tip().unwrap()].name.clone();
        let mut solver = IkSolver::new(chain.clone(), &tip, IkSettings::default()).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(2);
        let problems: Vec<(IkTarget, Vec<f64>)> = (0..256)
            .map(|_| {
                let mut goal = vec![0.0; chain.dof()];
                let mut seed = vec![0.0; chain.dof()];
                chain.random_configuration(&mut rng, &mut goal);
                chain.random_configuration(&mut rng, &mut seed);
                (IkTarget::Pose(solver.tool_pose(&goal).unwrap()), seed)
            })
            .collect();
        let mut k = 0;
        c.bench_function(&format!("ik_full_pose_random_seed/{robot}"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                let (target, seed) = &problems[k];
                black_box(solver.solve(target, seed, &mut rng).ok());
            })
        });
    }
}

criterion_group!(benches, fk, jacobian, ik);
criterion_main!(benches);
