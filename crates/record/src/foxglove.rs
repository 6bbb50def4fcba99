//! Foxglove-schema channels: the pitch, goals, robots and ball as a 3D scene.
//!
//! The scene is sent once (`foxglove.SceneUpdate`): the pitch in the `world`
//! frame, each robot and the ball as frame-locked primitives in a frame of
//! their own. Every tick then only moves those frames
//! (`foxglove.FrameTransforms`), which keeps recording cheap. The schemas
//! written into the file describe exactly the fields we emit, under the
//! published schema names, so Foxglove and Lichtblick pick their renderers;
//! a test checks the messages against the published schemas.

use std::io::Write;

use naosoccer_proto::{Team, ROBOTS};
use naosoccer_referee::Match;
use serde_json::{json, Value};

use crate::messages::StateRecord;

pub const SCENE_SCHEMA_NAME: &str = "foxglove.SceneUpdate";
pub const TF_SCHEMA_NAME: &str = "foxglove.FrameTransforms";

/// Frame ids of the robots, by robot index.
pub const ROBOT_FRAMES: [&str; ROBOTS] = [
    "robot_0", "robot_1", "robot_2", "robot_3", "robot_4", "robot_5", "robot_6", "robot_7",
];
pub const BALL_FRAME: &str = "ball";
pub const WORLD_FRAME: &str = "world";

fn vec3_schema() -> Value {
    json!({"type": "object", "required": ["x", "y", "z"],
           "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}})
}

fn quat_schema() -> Value {
    json!({"type": "object", "required": ["x", "y", "z", "w"],
           "properties": {"x": {"type": "number"}, "y": {"type": "number"},
                          "z": {"type": "number"}, "w": {"type": "number"}}})
}

fn color_schema() -> Value {
    json!({"type": "object", "required": ["r", "g", "b", "a"],
           "properties": {"r": {"type": "number"}, "g": {"type": "number"},
                          "b": {"type": "number"}, "a": {"type": "number"}}})
}

fn time_schema() -> Value {
    json!({"type": "object", "required": ["sec", "nsec"],
           "properties": {"sec": {"type": "integer", "minimum": 0},
                          "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
}

fn pose_schema() -> Value {
    json!({"type": "object", "required": ["position", "orientation"],
           "properties": {"position": vec3_schema(), "orientation": quat_schema()}})
}

fn shape_schema(extra: &[(&str, Value)]) -> Value {
    let mut props = serde_json::Map::new();
    props.insert("pose".into(), pose_schema());
    props.insert("size".into(), vec3_schema());
    props.insert("color".into(), color_schema());
    let mut required = vec![json!("pose"), json!("size"), json!("color")];
    for (k, v) in extra {
        props.insert((*k).into(), v.clone());
        required.push(json!(k));
    }
    json!({"type": "object", "required": required, "properties": props})
}

/// JSON Schema (draft 2020-12 subset) of the `foxglove.SceneUpdate` messages we write.
pub fn scene_schema() -> Vec<u8> {
    let line = json!({"type": "object",
        "required": ["type", "pose", "thickness", "scale_invariant", "points", "color", "colors", "indices"],
        "properties": {
            "type": {"type": "integer", "enum": [0, 1, 2]},
            "pose": pose_schema(), "thickness": {"type": "number"},
            "scale_invariant": {"type": "boolean"},
            "points": {"type": "array", "items": vec3_schema()},
            "color": color_schema(),
            "colors": {"type": "array", "items": color_schema()},
            "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}}}});
    let arrow = json!({"type": "object",
        "required": ["pose", "shaft_length", "shaft_diameter", "head_length", "head_diameter", "color"],
        "properties": {"pose": pose_schema(), "shaft_length": {"type": "number"},
            "shaft_diameter": {"type": "number"}, "head_length": {"type": "number"},
            "head_diameter": {"type": "number"}, "color": color_schema()}});
    let any_array = json!({"type": "array"});
    let entity = json!({"type": "object",
        "required": ["timestamp", "frame_id", "id", "lifetime", "frame_locked", "metadata",
                     "arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"],
        "properties": {
            "timestamp": time_schema(), "frame_id": {"type": "string"}, "id": {"type": "string"},
            "lifetime": time_schema(), "frame_locked": {"type": "boolean"},
            "metadata": {"type": "array", "items": {"type": "object", "required": ["key", "value"],
                "properties": {"key": {"type": "string"}, "value": {"type": "string"}}}},
            "arrows": {"type": "array", "items": arrow},
            "cubes": {"type": "array", "items": shape_schema(&[])},
            "spheres": {"type": "array", "items": shape_schema(&[])},
            "cylinders": {"type": "array", "items": shape_schema(&[
                ("bottom_scale", json!({"type": "number"})), ("top_scale", json!({"type": "number"}))])},
            "lines": {"type": "array", "items": line},
            "triangles": any_array, "texts": any_array, "models": any_array}});
    let schema = json!({
        "title": SCENE_SCHEMA_NAME,
        "description": "An update to the entities displayed in a 3D scene (the fields naosoccer writes)",
        "type": "object", "required": ["deletions", "entities"],
        "properties": {"deletions": {"type": "array"}, "entities": {"type": "array", "items": entity}}});
    serde_json::to_vec(&schema).expect("static schema serialises")
}

/// JSON Schema of the `foxglove.FrameTransforms` messages we write.
pub fn tf_schema() -> Vec<u8> {
    let schema = json!({
        "title": TF_SCHEMA_NAME,
        "description": "An array of FrameTransform messages",
        "type": "object", "required": ["transforms"],
        "properties": {"transforms": {"type": "array", "items": {
            "type": "object",
            "required": ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"],
            "properties": {"timestamp": time_schema(), "parent_frame_id": {"type": "string"},
                "child_frame_id": {"type": "string"}, "translation": vec3_schema(),
                "rotation": quat_schema()}}}}});
    serde_json::to_vec(&schema).expect("static schema serialises")
}

fn time(ns: u64) -> Value {
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

fn pose(x: f32, y: f32, z: f32) -> Value {
    json!({"position": {"x": x, "y": y, "z": z}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}})
}

fn rgba(r: f32, g: f32, b: f32, a: f32) -> Value {
    json!({"r": r, "g": g, "b": b, "a": a})
}

fn entity(ns: u64, frame: &str, id: &str, frame_locked: bool) -> serde_json::Map<String, Value> {
    let mut e = serde_json::Map::new();
    e.insert("timestamp".into(), time(ns));
    e.insert("frame_id".into(), json!(frame));
    e.insert("id".into(), json!(id));
    e.insert("lifetime".into(), time(0));
    e.insert("frame_locked".into(), json!(frame_locked));
    for k in [
        "metadata",
        "arrows",
        "cubes",
        "spheres",
        "cylinders",
        "lines",
        "triangles",
        "texts",
        "models",
    ] {
        e.insert(k.into(), json!([]));
    }
    e
}

fn cube(x: f32, y: f32, z: f32, sx: f32, sy: f32, sz: f32, color: Value) -> Value {
    json!({"pose": pose(x, y, z), "size": {"x": sx, "y": sy, "z": sz}, "color": color})
}

fn team_color(team: Team) -> Value {
    match team {
        Team::Blue => rgba(0.15, 0.35, 0.95, 1.0),
        Team::Red => rgba(0.9, 0.15, 0.15, 1.0),
    }
}

/// The whole scene, sent once at the start.
pub fn scene_update(m: &Match) -> Vec<u8> {
    let f = m.field();
    let sim = &m.config().sim;
    let (hl, hw) = (f.half_length, f.half_width);
    let margin = sim.ground_margin;
    let white = rgba(1.0, 1.0, 1.0, 1.0);

    let mut pitch = entity(0, WORLD_FRAME, "pitch", false);
    let grass = cube(
        0.0,
        0.0,
        -0.005,
        2.0 * (hl + margin.max(sim.goal_depth)),
        2.0 * (hw + margin),
        0.01,
        rgba(0.1, 0.5, 0.15, 1.0),
    );
    let p = |x: f32, y: f32| json!({"x": x, "y": y, "z": 0.002});
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
    let lines = json!([{"type": 2, "pose": pose(0.0, 0.0, 0.0), "thickness": 0.05,
        "scale_invariant": false, "points": segs, "color": white, "colors": [], "indices": []}]);
    pitch.insert("lines".into(), lines);

    // Goals: posts, crossbar and a translucent net box behind each line.
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
                white.clone(),
            ));
        }
        cubes.push(cube(
            x_line,
            0.0,
            gh + post / 2.0,
            post,
            2.0 * gw + 2.0 * post,
            post,
            white.clone(),
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
    pitch.insert("cubes".into(), Value::Array(cubes));

    let mut entities = vec![Value::Object(pitch)];
    for (i, frame) in ROBOT_FRAMES.iter().enumerate() {
        let team = if i < ROBOTS / 2 {
            Team::Blue
        } else {
            Team::Red
        };
        let color = team_color(team);
        let mut e = entity(0, frame, frame, true);
        // Torso origin is the frame origin; legs below, head above (NAO H25
        // proportions: torso origin about 0.33 m up, 0.57 m standing height).
        e.insert(
            "cylinders".into(),
            json!([{"pose": pose(0.0, 0.0, -0.17), "size": {"x": 0.16, "y": 0.2, "z": 0.32},
                "bottom_scale": 1.0, "top_scale": 1.0, "color": color.clone()}]),
        );
        e.insert(
            "cubes".into(),
            json!([cube(0.0, 0.0, 0.06, 0.1, 0.16, 0.2, color.clone())]),
        );
        e.insert(
            "spheres".into(),
            json!([{"pose": pose(0.0, 0.0, 0.21), "size": {"x": 0.12, "y": 0.12, "z": 0.12},
                "color": rgba(0.92, 0.92, 0.92, 1.0)}]),
        );
        e.insert(
            "arrows".into(),
            json!([{"pose": pose(0.05, 0.0, 0.06), "shaft_length": 0.12, "shaft_diameter": 0.02,
                "head_length": 0.05, "head_diameter": 0.05, "color": rgba(1.0, 0.85, 0.1, 1.0)}]),
        );
        e.insert(
            "metadata".into(),
            json!([{"key": "team", "value": team.to_string()},
                   {"key": "player", "value": (i % (ROBOTS / 2)).to_string()}]),
        );
        entities.push(Value::Object(e));
    }
    let mut ball = entity(0, BALL_FRAME, "ball", true);
    let d = 2.0 * f.ball_radius;
    ball.insert(
        "spheres".into(),
        json!([{"pose": pose(0.0, 0.0, 0.0), "size": {"x": d, "y": d, "z": d},
            "color": rgba(1.0, 0.55, 0.0, 1.0)}]),
    );
    entities.push(Value::Object(ball));
    serde_json::to_vec(&json!({"deletions": [], "entities": entities})).expect("scene serialises")
}

/// This tick's frame transforms, written into `out` (cleared first) without
/// building a JSON tree: it runs every tick.
pub fn write_transforms(out: &mut Vec<u8>, ns: u64, s: &StateRecord) {
    out.clear();
    let (sec, nsec) = (ns / 1_000_000_000, ns % 1_000_000_000);
    let tf = |out: &mut Vec<u8>, child: &str, t: [f32; 3], q: [f32; 4], last: bool| {
        // `{:?}` prints f32 in shortest round-trip form, which JSON accepts
        // as long as the value is finite (physics state always is).
        let _ = write!(
            out,
            r#"{{"timestamp":{{"sec":{sec},"nsec":{nsec}}},"parent_frame_id":"world","child_frame_id":"{child}","translation":{{"x":{:?},"y":{:?},"z":{:?}}},"rotation":{{"x":{:?},"y":{:?},"z":{:?},"w":{:?}}}}}{}"#,
            t[0],
            t[1],
            t[2],
            q[0],
            q[1],
            q[2],
            q[3],
            if last { "" } else { "," }
        );
    };
    out.extend_from_slice(br#"{"transforms":["#);
    for (i, r) in s.robots.iter().enumerate() {
        tf(out, ROBOT_FRAMES[i], [r.x, r.y, r.z], r.rotation, false);
    }
    let b = &s.ball;
    tf(out, BALL_FRAME, [b.x, b.y, b.z], [0.0, 0.0, 0.0, 1.0], true);
    out.extend_from_slice(b"]}");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::{BallRecord, ScoreRecord};
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
        let v: Value = serde_json::from_slice(&out).unwrap();
        let r = &v["transforms"][0]["rotation"];
        let got = [
            r["x"].as_f64().unwrap(),
            r["y"].as_f64().unwrap(),
            r["z"].as_f64().unwrap(),
            r["w"].as_f64().unwrap(),
        ];
        for (g, w) in got.iter().zip(on_back) {
            assert!((*g as f32 - w).abs() < 1e-6, "{got:?}");
        }
        assert_eq!(v["transforms"][0]["child_frame_id"], "robot_0");
    }
}
