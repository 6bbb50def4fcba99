//! Foxglove-schema channels: the pitch, goals, robots and ball as a 3D scene.
//!
//! The scene is sent once (`foxglove.SceneUpdate`): the pitch in the `world`
//! frame, each robot and the ball as frame-locked primitives in a frame of
//! their own. Every tick then only moves those frames
//! (`foxglove.FrameTransforms`), which keeps recording cheap.
//!
//! The messages are the Foxglove SDK's own types (`foxglove::messages`),
//! encoded as protobuf, and a channel's schema is the SDK's protobuf
//! descriptor of its type ([`schema`]), under the published schema name: no
//! hand-written schema can drift from what Foxglove and Lichtblick expect.
//! Protobuf encoding is a pure function of the message (fields in tag
//! order, no maps, the descriptors are constants), so the same match still
//! gives the same bytes.

use ::foxglove::messages::{
    line_primitive, ArrowPrimitive, Color, CubePrimitive, CylinderPrimitive, FrameTransform,
    FrameTransforms, KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity,
    SceneUpdate, SpherePrimitive, Timestamp, Vector3,
};
use ::foxglove::{Encode, Schema};
use naosoccer_proto::{Team, ROBOTS};
use naosoccer_referee::Match;

use crate::messages::StateRecord;

pub const SCENE_SCHEMA_NAME: &str = "foxglove.SceneUpdate";
pub const TF_SCHEMA_NAME: &str = "foxglove.FrameTransforms";
/// The message encoding of the Foxglove channels (their schemas' encoding
/// is `protobuf` too).
pub const ENCODING: &str = "protobuf";

/// Frame ids of the robots, by robot index.
pub const ROBOT_FRAMES: [&str; ROBOTS] = [
    "robot_0", "robot_1", "robot_2", "robot_3", "robot_4", "robot_5", "robot_6", "robot_7",
];
pub const BALL_FRAME: &str = "ball";
pub const WORLD_FRAME: &str = "world";

/// The SDK's schema of a Foxglove message type: its published name
/// (`foxglove.SceneUpdate`, ...), encoding `protobuf`, and the protobuf
/// descriptor (a `FileDescriptorSet`) as data.
pub fn schema<T: Encode>() -> Schema {
    T::get_schema().expect("the SDK's Foxglove types have schemas")
}

/// `msg` protobuf-encoded into `out` (cleared first).
pub fn encode_into<T: Encode>(out: &mut Vec<u8>, msg: &T) {
    out.clear();
    // Only a full fixed-size buffer fails; a Vec grows.
    msg.encode(out).expect("encoding into a Vec cannot fail");
}

/// `msg` protobuf-encoded.
pub fn encode<T: Encode>(msg: &T) -> Vec<u8> {
    let mut out = Vec::with_capacity(msg.encoded_len().unwrap_or(256));
    encode_into(&mut out, msg);
    out
}

/// A protobuf timestamp of `ns` nanoseconds (game time in a recording,
/// Unix time live).
pub fn timestamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000) as u32, (ns % 1_000_000_000) as u32)
}

fn vec3(x: f32, y: f32, z: f32) -> Option<Vector3> {
    Some(Vector3 {
        x: x.into(),
        y: y.into(),
        z: z.into(),
    })
}

/// An upright pose at (x, y, z).
pub fn pose(x: f32, y: f32, z: f32) -> Option<Pose> {
    Some(Pose {
        position: vec3(x, y, z),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    })
}

pub fn rgba(r: f32, g: f32, b: f32, a: f32) -> Option<Color> {
    Some(Color {
        r: r.into(),
        g: g.into(),
        b: b.into(),
        a: a.into(),
    })
}

/// An empty entity `id` in `frame`, stamped at time 0 (it lives until
/// replaced).
pub fn entity(frame: &str, id: &str, frame_locked: bool) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(0)),
        frame_id: frame.into(),
        id: id.into(),
        frame_locked,
        ..SceneEntity::default()
    }
}

fn cube(x: f32, y: f32, z: f32, sx: f32, sy: f32, sz: f32, color: Option<Color>) -> CubePrimitive {
    CubePrimitive {
        pose: pose(x, y, z),
        size: vec3(sx, sy, sz),
        color,
    }
}

fn team_color(team: Team) -> Option<Color> {
    match team {
        Team::Blue => rgba(0.15, 0.35, 0.95, 1.0),
        Team::Red => rgba(0.9, 0.15, 0.15, 1.0),
    }
}

/// The pitch: grass, lines and the two goals (posts, crossbar, a
/// translucent net box behind each line), in the `world` frame.
pub fn pitch(m: &Match) -> SceneEntity {
    let f = m.field();
    let sim = &m.config().sim;
    let (hl, hw) = (f.half_length, f.half_width);
    let margin = sim.ground_margin;
    let white = rgba(1.0, 1.0, 1.0, 1.0);

    let mut pitch = entity(WORLD_FRAME, "pitch", false);
    let grass = cube(
        0.0,
        0.0,
        -0.005,
        2.0 * (hl + margin.max(sim.goal_depth)),
        2.0 * (hw + margin),
        0.01,
        rgba(0.1, 0.5, 0.15, 1.0),
    );
    let p = |x: f32, y: f32| Point3 {
        x: x.into(),
        y: y.into(),
        z: 0.002f32.into(),
    };
    let mut segs = vec![
        p(-hl, -hw),
        p(hl, -hw),
        p(hl, -hw),
        p(hl, hw),
        p(hl, hw),
        p(-hl, hw),
        p(-hl, hw),
        p(-hl, -hw),
        p(0.0, -hw),
        p(0.0, hw),
    ];
    // The centre circle as 32 segments (0.75 m radius, as in the SPL).
    let r = 0.75;
    for i in 0..32 {
        let a0 = i as f32 / 32.0 * std::f32::consts::TAU;
        let a1 = (i + 1) as f32 / 32.0 * std::f32::consts::TAU;
        segs.push(p(r * a0.cos(), r * a0.sin()));
        segs.push(p(r * a1.cos(), r * a1.sin()));
    }
    pitch.lines = vec![LinePrimitive {
        r#type: line_primitive::Type::LineList as i32,
        pose: pose(0.0, 0.0, 0.0),
        thickness: 0.05f32.into(),
        scale_invariant: false,
        points: segs,
        color: white,
        colors: Vec::new(),
        indices: Vec::new(),
    }];

    let gw = f.goal_half_width;
    let gh = f.crossbar;
    let post = sim.goal_post_size;
    let depth = sim.goal_depth;
    let mut cubes = vec![grass];
    for side in [-1.0f32, 1.0] {
        let x_line = side * (hl + post / 2.0);
        for y in [-(gw + post / 2.0), gw + post / 2.0] {
            cubes.push(cube(
                x_line,
                y,
                (gh + post) / 2.0,
                post,
                post,
                gh + post,
                white,
            ));
        }
        cubes.push(cube(
            x_line,
            0.0,
            gh + post / 2.0,
            post,
            2.0 * gw + 2.0 * post,
            post,
            white,
        ));
        cubes.push(cube(
            side * (hl + depth / 2.0),
            0.0,
            gh / 2.0,
            depth,
            2.0 * gw,
            gh,
            rgba(0.9, 0.9, 0.9, 0.25),
        ));
    }
    pitch.cubes = cubes;
    pitch
}

/// The robots (`robot_0`…`robot_7`) and the ball (`ball`), each a
/// frame-locked entity in its own frame: the transforms move them.
pub fn bodies(m: &Match) -> Vec<SceneEntity> {
    let f = m.field();
    let mut entities = Vec::with_capacity(ROBOTS + 1);
    for (i, frame) in ROBOT_FRAMES.iter().enumerate() {
        let team = if i < ROBOTS / 2 {
            Team::Blue
        } else {
            Team::Red
        };
        let color = team_color(team);
        let mut e = entity(frame, frame, true);
        // Torso origin is the frame origin; legs below, head above (NAO H25
        // proportions: torso origin about 0.33 m up, 0.57 m standing height).
        e.cylinders = vec![CylinderPrimitive {
            pose: pose(0.0, 0.0, -0.17),
            size: vec3(0.16, 0.2, 0.32),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color,
        }];
        e.cubes = vec![cube(0.0, 0.0, 0.06, 0.1, 0.16, 0.2, color)];
        e.spheres = vec![SpherePrimitive {
            pose: pose(0.0, 0.0, 0.21),
            size: vec3(0.12, 0.12, 0.12),
            color: rgba(0.92, 0.92, 0.92, 1.0),
        }];
        e.arrows = vec![ArrowPrimitive {
            pose: pose(0.05, 0.0, 0.06),
            shaft_length: 0.12f32.into(),
            shaft_diameter: 0.02f32.into(),
            head_length: 0.05f32.into(),
            head_diameter: 0.05f32.into(),
            color: rgba(1.0, 0.85, 0.1, 1.0),
        }];
        e.metadata = vec![
            KeyValuePair {
                key: "team".into(),
                value: team.to_string(),
            },
            KeyValuePair {
                key: "player".into(),
                value: (i % (ROBOTS / 2)).to_string(),
            },
        ];
        entities.push(e);
    }
    let mut ball = entity(BALL_FRAME, BALL_FRAME, true);
    let d = 2.0 * f.ball_radius;
    ball.spheres = vec![SpherePrimitive {
        pose: pose(0.0, 0.0, 0.0),
        size: vec3(d, d, d),
        color: rgba(1.0, 0.55, 0.0, 1.0),
    }];
    entities.push(ball);
    entities
}

/// The whole scene, sent once at the start: the pitch, then the robots and
/// the ball.
pub fn scene_update(m: &Match) -> SceneUpdate {
    let mut entities = vec![pitch(m)];
    entities.extend(bodies(m));
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}

/// This tick's frame transforms, `world` → `robot_i` (the recorded torso
/// position and `rotation`) and `world` → `ball`, stamped `ns`.
pub fn transforms(ns: u64, s: &StateRecord) -> FrameTransforms {
    let stamp = Some(timestamp(ns));
    let tf = |child: &str, t: [f32; 3], q: [f32; 4]| FrameTransform {
        timestamp: stamp,
        parent_frame_id: WORLD_FRAME.into(),
        child_frame_id: child.into(),
        translation: vec3(t[0], t[1], t[2]),
        rotation: Some(Quaternion {
            x: q[0].into(),
            y: q[1].into(),
            z: q[2].into(),
            w: q[3].into(),
        }),
    };
    let mut transforms: Vec<FrameTransform> = s
        .robots
        .iter()
        .zip(ROBOT_FRAMES)
        .map(|(r, frame)| tf(frame, [r.x, r.y, r.z], r.rotation))
        .collect();
    let b = &s.ball;
    transforms.push(tf(BALL_FRAME, [b.x, b.y, b.z], [0.0, 0.0, 0.0, 1.0]));
    FrameTransforms { transforms }
}

/// [`transforms`] protobuf-encoded into `out` (cleared first): it runs
/// every tick.
pub fn write_transforms(out: &mut Vec<u8>, ns: u64, s: &StateRecord) {
    encode_into(out, &transforms(ns, s));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{BallRecord, ScoreRecord};
    use ::foxglove::Decode;
    use naosoccer_proto::Tick;

    fn state(rotation: [f32; 4]) -> StateRecord {
        let robot = crate::messages::RobotRecord {
            x: 1.0,
            y: 2.0,
            z: 0.06,
            heading: 0.0,
            tilt: 1.57,
            rotation,
            fallen: true,
        };
        StateRecord {
            tick: Tick::new(3),
            time: 0.3,
            score: ScoreRecord { blue: 0, red: 0 },
            possession: None,
            ball: BallRecord {
                x: 0.0,
                y: 0.0,
                z: 0.05,
                vx: 0.0,
                vy: 0.0,
                vz: 0.0,
            },
            robots: [robot; ROBOTS],
            state_hash: "0".repeat(16),
        }
    }

    /// Issue 12: the transform carries the recorded orientation itself, so
    /// a robot lying on its back is drawn on its back (a yaw-and-tilt
    /// rebuild drew every fallen robot face down).
    #[test]
    fn issue_12_the_transform_is_the_recorded_rotation() {
        // On its back: pitched -90 degrees about y (x axis pointing up).
        let h = std::f32::consts::FRAC_PI_4;
        let on_back = [0.0, -h.sin(), 0.0, h.cos()];
        let mut out = Vec::new();
        write_transforms(&mut out, 300_000_000, &state(on_back));
        let v = FrameTransforms::decode(out.as_slice()).unwrap();
        let t = &v.transforms[0];
        let r = t.rotation.unwrap();
        let got = [r.x, r.y, r.z, r.w];
        for (g, w) in got.iter().zip(on_back) {
            assert!((*g as f32 - w).abs() < 1e-6, "{got:?}");
        }
        assert_eq!(t.child_frame_id, "robot_0");
        assert_eq!(t.parent_frame_id, "world");
        assert_eq!(t.timestamp, Some(Timestamp::new(0, 300_000_000)));
        assert_eq!(v.transforms.len(), ROBOTS + 1);
        assert_eq!(v.transforms[ROBOTS].child_frame_id, "ball");
    }

    /// The channels' schemas are the SDK's protobuf descriptors under the
    /// published names.
    #[test]
    fn schemas_are_the_sdks_protobuf_descriptors() {
        let scene = schema::<SceneUpdate>();
        assert_eq!(scene.name, SCENE_SCHEMA_NAME);
        assert_eq!(scene.encoding, ENCODING);
        let tf = schema::<FrameTransforms>();
        assert_eq!(tf.name, TF_SCHEMA_NAME);
        assert_eq!(tf.encoding, ENCODING);
        // A FileDescriptorSet naming the message's package file.
        let needle = b"foxglove/SceneUpdate.proto";
        assert!(scene.data.windows(needle.len()).any(|w| w == needle));
    }

    /// Encoding is a pure function of the scene: the same match, the same
    /// bytes; and they decode to the pitch, eight robots and the ball.
    #[test]
    fn the_scene_encodes_repeatably_and_decodes_whole() {
        let cfg = naosoccer_referee::MatchConfig::default();
        let a = encode(&scene_update(&Match::new(&cfg, 1).unwrap()));
        let b = encode(&scene_update(&Match::new(&cfg, 1).unwrap()));
        assert_eq!(a, b);
        let s = SceneUpdate::decode(a.as_slice()).unwrap();
        let ids: Vec<&str> = s.entities.iter().map(|e| e.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "pitch", "robot_0", "robot_1", "robot_2", "robot_3", "robot_4", "robot_5",
                "robot_6", "robot_7", "ball"
            ]
        );
        assert_eq!(s.entities[0].cubes.len(), 1 + 2 * 4, "grass and two goals");
        assert_eq!(s.entities[0].lines[0].points.len(), 10 + 64);
        assert!(s.entities[1..].iter().all(|e| e.frame_locked));
    }
}
