"""assets/nao.urdf read by a standard URDF 1.0 tool (yourdfpy), not our loader.

The robot file must open in the tools people use (yourdfpy, urdfpy, RViz): it
is URDF 1.0, with the foot rollers written as `<cylinder>` collisions named
`*_capsule` that our loader turns into capsules (URDF 1.0 has no capsule; a
`<capsule>` tag made yourdfpy fail with "Unknown tag: capsule"). What yourdfpy
reads must be the robot the simulation uses: the figures below are the Rust
model's (`RobotModel::builtin()`), pinned to the same values by
`crates/sim/tests/sim.rs` (`the_model_is_the_one_urdf_tools_read`).
"""

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

yourdfpy = pytest.importorskip("yourdfpy")

REPO = Path(__file__).resolve().parents[2]
URDF = REPO / "assets" / "nao.urdf"

# The Rust model: RobotModel::total_mass(), dof(), joints().len(),
# standing_height() and torso_height() (soles to torso origin).
TOTAL_MASS_KG = 5.27072
DOF = 25
MOVABLE_JOINTS = 26
STANDING_HEIGHT_M = 0.57559
TORSO_HEIGHT_M = 0.33309

# STANDING_POSE in crates/sim/src/model.rs; joints not listed stand at zero.
STANDING_POSE = {
    "LShoulderPitch": 1.45,
    "RShoulderPitch": 1.45,
    "LShoulderRoll": 0.12,
    "RShoulderRoll": -0.12,
    "LElbowYaw": -1.2,
    "RElbowYaw": 1.2,
    "LElbowRoll": -0.4,
    "RElbowRoll": 0.4,
}


@pytest.fixture(scope="module")
def robot():
    return yourdfpy.URDF.load(
        str(URDF), build_collision_scene_graph=True, load_collision_meshes=True
    )


def test_the_file_is_urdf_1_0():
    tags = {e.tag for e in ET.parse(URDF).iter()}
    assert "capsule" not in tags, "URDF 1.1's <capsule> breaks URDF 1.0 tools"


def test_total_mass_is_the_models(robot):
    mass = sum(link.inertial.mass for link in robot.robot.links if link.inertial)
    assert mass == pytest.approx(TOTAL_MASS_KG, abs=1e-4)


def test_joints_are_the_models(robot):
    joints = {j.name: j for j in robot.robot.joints if j.type != "fixed"}
    assert len(joints) == MOVABLE_JOINTS
    assert sum(1 for j in joints.values() if j.mimic is None) == DOF
    assert joints["RHipYawPitch"].mimic.joint == "LHipYawPitch"
    knee = joints["LKneePitch"].limit
    assert (knee.lower, knee.upper) == pytest.approx((-0.092346, 2.112528))


def test_standing_height_is_the_models(robot):
    cfg = [STANDING_POSE.get(name, 0.0) for name in robot.actuated_joint_names]
    robot.update_cfg(cfg)
    (_, _, lo), (_, _, hi) = robot.collision_scene.bounds
    # The rollers' bottoms are the soles, the head sphere's top the top;
    # a cylinder and a capsule across the soles reach equally low.
    assert -lo == pytest.approx(TORSO_HEIGHT_M, abs=1e-3)
    assert hi - lo == pytest.approx(STANDING_HEIGHT_M, abs=1e-3)


def test_the_rollers_are_the_named_cylinders(robot):
    torso = next(link for link in robot.robot.links if link.name == "torso")
    rollers = [c for c in torso.collisions if c.geometry.cylinder is not None]
    assert sorted(c.name for c in rollers) == ["heel_roller_capsule", "toe_roller_capsule"]
    for c in rollers:
        assert c.geometry.cylinder.radius == pytest.approx(0.015)
        assert c.geometry.cylinder.length == pytest.approx(0.158)
