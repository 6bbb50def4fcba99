//! The robot as the physics sees it: the URDF's collision primitives and link
//! inertias, placed by forward kinematics in the standing pose and expressed
//! in the torso frame. One rigid body per robot carries all of them.

use std::path::Path;

use rapier3d::math::{Mat3, Pose, Rot3, Vec3};
use rapier3d::prelude::MassProperties;

use crate::SimError;

/// The URDF shipped with the project (`assets/nao.urdf`).
pub const NAO_URDF: &str = include_str!("../../../assets/nao.urdf");

/// Name of the root link whose frame is the robot body's frame.
pub const ROOT_LINK: &str = "torso";

/// Joint angles of the standing pose, radians: legs straight, arms hanging
/// beside the body with the elbows slightly bent. Joints not listed stand at
/// zero; every angle is clamped to the joint's limits.
pub const STANDING_POSE: &[(&str, f32)] = &[
    ("LShoulderPitch", 1.45),
    ("RShoulderPitch", 1.45),
    ("LShoulderRoll", 0.12),
    ("RShoulderRoll", -0.12),
    ("LElbowYaw", -1.2),
    ("RElbowYaw", 1.2),
    ("LElbowRoll", -0.4),
    ("RElbowRoll", 0.4),
];

/// A `<cylinder>` collision whose `name` ends with this is a capsule: the
/// cylinder's `radius`, and its `length` the distance between the centres
/// of the two hemispheres that round it off (as URDF 1.1's `<capsule>`
/// reads it). URDF 1.0 has no capsule, so the file says `<cylinder>` and
/// every URDF tool reads it (and draws the capsule without its rounded
/// ends); this loader makes it the capsule. A cylinder named otherwise is a
/// cylinder. URDF 1.1's `<capsule>` is read too.
pub const CAPSULE_SUFFIX: &str = "_capsule";

/// One collision primitive of a link, placed in the torso frame.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionShape {
    /// The URDF link it belongs to.
    pub link: String,
    /// Its geometry.
    pub primitive: Primitive,
    /// Its pose in the torso frame, standing pose.
    pub pose: Pose,
}

/// A URDF collision primitive, in metres. URDF cylinders have their axis
/// along the local z axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// A box given by its half extents.
    Cuboid { half_extents: Vec3 },
    /// A sphere.
    Sphere { radius: f32 },
    /// A cylinder along local z.
    Cylinder { radius: f32, half_length: f32 },
    /// A capsule along local z: a cylinder of `half_length` with a
    /// hemisphere of `radius` on each end (URDF `length` is the cylinder's).
    Capsule { radius: f32, half_length: f32 },
}

/// A revolute (or other movable) joint of the model, with its limits.
#[derive(Debug, Clone, PartialEq)]
pub struct JointInfo {
    pub name: String,
    /// Lower position limit, rad.
    pub lower: f32,
    /// Upper position limit, rad.
    pub upper: f32,
    /// Name of the joint it mimics (the same motor), if any.
    pub mimics: Option<String>,
}

/// A robot model built from a URDF in the standing pose.
#[derive(Debug, Clone)]
pub struct RobotModel {
    name: String,
    links: usize,
    joints: Vec<JointInfo>,
    shapes: Vec<CollisionShape>,
    mass: MassProperties,
    /// Lowest point of the collision geometry in the torso frame (z < 0).
    sole_z: f32,
    /// Highest point of the collision geometry in the torso frame.
    top_z: f32,
}

impl RobotModel {
    /// The project's NAO H25 (`assets/nao.urdf`, compiled in). Parsed once
    /// per process and cloned after: parsing the XML cost about as much as
    /// building the rest of a match's world (a drill builds a match per
    /// start), and the same text always parses to the same model.
    pub fn builtin() -> Result<RobotModel, SimError> {
        static PARSED: std::sync::OnceLock<RobotModel> = std::sync::OnceLock::new();
        if let Some(m) = PARSED.get() {
            return Ok(m.clone());
        }
        let m = RobotModel::from_urdf_str(NAO_URDF)?;
        Ok(PARSED.get_or_init(|| m).clone())
    }

    /// Reads a URDF file.
    pub fn from_urdf_file(path: &Path) -> Result<RobotModel, SimError> {
        let text = std::fs::read_to_string(path).map_err(|e| SimError::Io {
            path: path.display().to_string(),
            source: e,
        })?;
        RobotModel::from_urdf_str(&text)
    }

    /// Parses a URDF document and places it in [`STANDING_POSE`].
    pub fn from_urdf_str(text: &str) -> Result<RobotModel, SimError> {
        let robot = urdf_rs::read_from_string(text).map_err(|e| SimError::Urdf(e.to_string()))?;
        RobotModel::from_urdf(&robot)
    }

    /// Builds the model from a parsed URDF in [`STANDING_POSE`].
    pub fn from_urdf(robot: &urdf_rs::Robot) -> Result<RobotModel, SimError> {
        let n = robot.links.len();
        if robot.links.iter().all(|l| l.name != ROOT_LINK) {
            return Err(SimError::Urdf(format!("no link named `{ROOT_LINK}`")));
        }
        let link_index = |name: &str| -> Result<usize, SimError> {
            robot
                .links
                .iter()
                .position(|l| l.name == name)
                .ok_or_else(|| SimError::Urdf(format!("joint refers to unknown link `{name}`")))
        };

        let mut joints = Vec::new();
        for j in &robot.joints {
            if j.joint_type == urdf_rs::JointType::Fixed {
                continue;
            }
            joints.push(JointInfo {
                name: j.name.clone(),
                lower: j.limit.lower as f32,
                upper: j.limit.upper as f32,
                mimics: j.mimic.as_ref().map(|m| m.joint.clone()),
            });
        }
        let angle_of = |name: &str| -> f32 {
            STANDING_POSE
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(0.0, |(_, a)| *a)
        };

        // Link poses in the torso frame, found by repeatedly placing children
        // of already placed links: the tree is small, quadratic is fine.
        let mut pose: Vec<Option<Pose>> = vec![None; n];
        pose[link_index(ROOT_LINK)?] = Some(Pose::IDENTITY);
        let mut placed = 1;
        let mut progress = true;
        while progress {
            progress = false;
            for j in &robot.joints {
                let p = link_index(&j.parent.link)?;
                let c = link_index(&j.child.link)?;
                let (Some(parent), None) = (pose[p], pose[c]) else {
                    continue;
                };
                let mut q =
                    match &j.mimic {
                        Some(m) => {
                            let master =
                                robot.joints.iter().find(|k| k.name == m.joint).ok_or_else(
                                    || {
                                        SimError::Urdf(format!(
                                            "joint `{}` mimics unknown joint `{}`",
                                            j.name, m.joint
                                        ))
                                    },
                                )?;
                            angle_of(&master.name) * m.multiplier.unwrap_or(1.0) as f32
                                + m.offset.unwrap_or(0.0) as f32
                        }
                        None => angle_of(&j.name),
                    };
                let movable = matches!(
                    j.joint_type,
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
                );
                if j.joint_type == urdf_rs::JointType::Revolute {
                    q = q.clamp(j.limit.lower as f32, j.limit.upper as f32);
                }
                let mut local = urdf_pose(&j.origin);
                if movable {
                    let axis = vec3(&j.axis.xyz);
                    let len = axis.length();
                    if len.is_nan() || len <= 1e-6 {
                        return Err(SimError::Urdf(format!(
                            "joint `{}` has a zero axis",
                            j.name
                        )));
                    }
                    local *= Pose::from_rotation(Rot3::from_axis_angle(axis / len, q));
                }
                pose[c] = Some(parent * local);
                placed += 1;
                progress = true;
            }
        }
        if placed != n {
            let missing: Vec<&str> = robot
                .links
                .iter()
                .zip(&pose)
                .filter(|(_, p)| p.is_none())
                .map(|(l, _)| l.name.as_str())
                .collect();
            return Err(SimError::Urdf(format!(
                "links not connected to `{ROOT_LINK}`: {}",
                missing.join(", ")
            )));
        }

        let mut shapes = Vec::new();
        let mut mass = MassProperties::default();
        let mut sole_z = f32::INFINITY;
        let mut top_z = f32::NEG_INFINITY;
        for (link, link_pose) in robot.links.iter().zip(&pose) {
            let link_pose = link_pose.expect("all links placed above");
            let m = link.inertial.mass.value as f32;
            if !(m.is_finite() && m >= 0.0) {
                return Err(SimError::Urdf(format!("link `{}` has mass {m}", link.name)));
            }
            if m > 0.0 {
                let i = &link.inertial.inertia;
                let tensor = Mat3::from_cols(
                    Vec3::new(i.ixx as f32, i.ixy as f32, i.ixz as f32),
                    Vec3::new(i.ixy as f32, i.iyy as f32, i.iyz as f32),
                    Vec3::new(i.ixz as f32, i.iyz as f32, i.izz as f32),
                );
                let frame = link_pose * urdf_pose(&link.inertial.origin);
                let local = MassProperties::with_inertia_matrix(Vec3::ZERO, m, tensor);
                mass += local.transform_by(&frame);
            }
            for c in &link.collision {
                let primitive = match &c.geometry {
                    urdf_rs::Geometry::Box { size } => Primitive::Cuboid {
                        half_extents: vec3(size) * 0.5,
                    },
                    urdf_rs::Geometry::Sphere { radius } => Primitive::Sphere {
                        radius: *radius as f32,
                    },
                    urdf_rs::Geometry::Cylinder { radius, length }
                        if c.name.as_deref().is_some_and(|n| n.ends_with(CAPSULE_SUFFIX)) =>
                    {
                        Primitive::Capsule {
                            radius: *radius as f32,
                            half_length: *length as f32 * 0.5,
                        }
                    }
                    urdf_rs::Geometry::Cylinder { radius, length } => Primitive::Cylinder {
                        radius: *radius as f32,
                        half_length: *length as f32 * 0.5,
                    },
                    urdf_rs::Geometry::Capsule { radius, length } => Primitive::Capsule {
                        radius: *radius as f32,
                        half_length: *length as f32 * 0.5,
                    },
                    other => {
                        return Err(SimError::Urdf(format!(
                            "link `{}`: only box, sphere, cylinder and capsule collisions are supported, got {other:?}",
                            link.name
                        )))
                    }
                };
                let pose = link_pose * urdf_pose(&c.origin);
                let (lo, hi) = z_extent(&primitive, &pose);
                sole_z = sole_z.min(lo);
                top_z = top_z.max(hi);
                shapes.push(CollisionShape {
                    link: link.name.clone(),
                    primitive,
                    pose,
                });
            }
        }
        if shapes.is_empty() {
            return Err(SimError::Urdf("the model has no collision geometry".into()));
        }
        if mass.mass().is_nan() || mass.mass() <= 0.0 {
            return Err(SimError::Urdf("the model has no mass".into()));
        }
        Ok(RobotModel {
            name: robot.name.clone(),
            links: n,
            joints,
            shapes,
            mass,
            sole_z,
            top_z,
        })
    }

    /// The URDF robot name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of links.
    pub fn link_count(&self) -> usize {
        self.links
    }

    /// Movable joints (including mimic joints).
    pub fn joints(&self) -> &[JointInfo] {
        &self.joints
    }

    /// Degrees of freedom: movable joints that do not mimic another.
    pub fn dof(&self) -> usize {
        self.joints.iter().filter(|j| j.mimics.is_none()).count()
    }

    /// Collision primitives in the torso frame, standing pose.
    pub fn collision_shapes(&self) -> &[CollisionShape] {
        &self.shapes
    }

    /// Sum of the link masses, kg.
    pub fn total_mass(&self) -> f32 {
        self.mass.mass()
    }

    /// Mass, centre of mass and inertia of the whole robot in the torso frame.
    pub fn mass_properties(&self) -> MassProperties {
        self.mass
    }

    /// Height of the torso origin above the soles when standing, metres.
    pub fn torso_height(&self) -> f32 {
        -self.sole_z
    }

    /// Standing height, soles to the top of the head, metres.
    pub fn standing_height(&self) -> f32 {
        self.top_z - self.sole_z
    }

    /// Forward reach of the soles from the torso origin, metres (toe tip).
    pub fn toe_x(&self) -> f32 {
        self.shapes
            .iter()
            .filter(|s| {
                let (lo, _) = z_extent(&s.primitive, &s.pose);
                lo <= self.sole_z + 1e-4
            })
            .map(|s| x_extent(&s.primitive, &s.pose).1)
            .fold(f32::NEG_INFINITY, f32::max)
    }
}

fn vec3(v: &urdf_rs::Vec3) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// URDF origin: translation, then fixed-axis roll-pitch-yaw (Rz * Ry * Rx).
fn urdf_pose(p: &urdf_rs::Pose) -> Pose {
    let r = Rot3::from_rotation_z(p.rpy[2] as f32)
        * Rot3::from_rotation_y(p.rpy[1] as f32)
        * Rot3::from_rotation_x(p.rpy[0] as f32);
    Pose::from_parts(vec3(&p.xyz), r)
}

/// Support of a primitive along a world direction `d` (unit), placed at `pose`.
fn support(p: &Primitive, pose: &Pose, d: Vec3) -> f32 {
    let centre = pose.translation.dot(d);
    let local = pose.rotation.inverse() * d;
    centre
        + match *p {
            Primitive::Cuboid { half_extents } => local.abs().dot(half_extents),
            Primitive::Sphere { radius } => radius,
            Primitive::Cylinder {
                radius,
                half_length,
            } => local.z.abs() * half_length + radius * (1.0 - local.z * local.z).max(0.0).sqrt(),
            Primitive::Capsule {
                radius,
                half_length,
            } => local.z.abs() * half_length + radius,
        }
}

pub(crate) fn z_extent(p: &Primitive, pose: &Pose) -> (f32, f32) {
    (-support(p, pose, -Vec3::Z), support(p, pose, Vec3::Z))
}

fn x_extent(p: &Primitive, pose: &Pose) -> (f32, f32) {
    (-support(p, pose, -Vec3::X), support(p, pose, Vec3::X))
}
