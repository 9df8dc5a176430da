#!/usr/bin/env python3
"""PyBullet side of `hearth bench sim`: steps an exported Hearth home at the same timestep.

    hearth scene generate --seed 1 --out home.json
    hearth scene export home.json --robot fetch --urdf-dir home_urdf
    python3 benches/peers/pybullet_scene.py home_urdf [--steps 600] [--no-robot] [--json out.json]

Loads every body of `home_urdf/scene.json` (fixed bodies with a fixed base; the robot's joints
held where they start by position motors), settles 240 steps, then times `--steps` physics
steps of 1/120 s in chunks of 60 and prints the median rate. PyBullet does not put bodies to
sleep unless asked, so this is the all-awake figure to compare with `hearth bench sim --no-sleep`.
Needs `pip install pybullet` (a benchmark peer, not a dependency of Hearth).
"""
import argparse
import json
import os
import statistics
import time

import pybullet as p


def load(dir_, with_robot):
    manifest = json.load(open(os.path.join(dir_, "scene.json")))
    bodies = 0
    robot = None
    for b in manifest["bodies"]:
        if b.get("robot") and not with_robot:
            continue
        uid = p.loadURDF(
            os.path.join(dir_, b["urdf"]),
            basePosition=b["position"],
            baseOrientation=b["quat_xyzw"],
            useFixedBase=bool(b["fixed"]),
            flags=p.URDF_USE_INERTIA_FROM_FILE,
        )
        bodies += 1
        for name, value in (b.get("joints") or {}).items():
            for j in range(p.getNumJoints(uid)):
                if p.getJointInfo(uid, j)[1].decode() == name:
                    p.resetJointState(uid, j, value)
        if b.get("robot"):
            robot = uid
    if robot is not None:
        joints = [j for j in range(p.getNumJoints(robot)) if p.getJointInfo(robot, j)[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC)]
        targets = [p.getJointState(robot, j)[0] for j in joints]
        p.setJointMotorControlArray(robot, joints, p.POSITION_CONTROL, targetPositions=targets)
    return bodies, robot is not None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--no-robot", action="store_true")
    ap.add_argument("--json")
    a = ap.parse_args()
    p.connect(p.DIRECT)
    p.setGravity(0, 0, -9.81)
    p.setTimeStep(1.0 / 120.0)
    t0 = time.perf_counter()
    bodies, robot = load(a.dir, not a.no_robot)
    load_s = time.perf_counter() - t0
    for _ in range(240):
        p.stepSimulation()
    rates = []
    done = 0
    while done < a.steps:
        n = min(60, a.steps - done)
        t = time.perf_counter()
        for _ in range(n):
            p.stepSimulation()
        rates.append(n / (time.perf_counter() - t))
        done += n
    out = {"engine": "pybullet", "physics_hz_median": statistics.median(rates), "bodies": bodies, "robot": robot,
           "load_s": load_s, "steps": a.steps}
    print(json.dumps(out))
    if a.json:
        json.dump(out, open(a.json, "w"))


if __name__ == "__main__":
    main()
