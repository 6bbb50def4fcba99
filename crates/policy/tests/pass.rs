//! A team with the `pass` action plays it only where the observation says a
//! pass is possible (ball in kick reach, a receiver named by the protocol's
//! pass rule), in process exactly as over the socket; a team with the
//! `support` action walks to where a pass can reach it.

use std::f32::consts::PI;
use std::path::Path;

use naosoccer_client::Policy;
use naosoccer_policy::{LearnedPolicy, PlayConfig, Weights, PASS, SUPPORT};
use naosoccer_proto::{Action, Team, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

/// The shipped seed-1 team given a sixth output whose bias makes `pass`
/// the greedy choice wherever it is allowed.
fn pass_loving_team() -> LearnedPolicy {
    loving_team(PASS)
}

/// The shipped seed-1 team given outputs up to `favourite` (`pass`, or
/// `pass` and `support`), the last with a bias that makes it the greedy
/// choice wherever it is allowed.
fn loving_team(favourite: usize) -> LearnedPolicy {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/policies/ppo-team-seed1");
    let mut cfg = PlayConfig::read(&dir.join("config.json")).unwrap();
    let d = cfg.ppo.decision.as_mut().unwrap();
    d.pass = true;
    d.support = favourite == SUPPORT;
    let extra = favourite + 1 - five_outputs(&dir);
    let five = Weights::read(&dir.join("final.safetensors")).unwrap();
    let mut w = Weights::default();
    let last = five
        .names()
        .filter(|n| n.starts_with("actor.") && n.ends_with(".bias"))
        .max()
        .unwrap()
        .trim_end_matches(".bias")
        .to_string();
    for name in five.names() {
        let (shape, data) = five.get(name).unwrap();
        let (mut shape, mut data) = (shape.to_vec(), data.to_vec());
        if name == format!("{last}.weight") {
            data.extend(std::iter::repeat_n(0.0, shape[1] * extra));
            shape[0] += extra;
        } else if name == format!("{last}.bias") {
            data.extend(std::iter::repeat_n(0.0, extra - 1));
            data.push(1e3);
            shape[0] += extra;
        }
        w.insert(name, shape, data);
    }
    let mut team = LearnedPolicy::from_weights(&cfg, &w, "loving".into()).unwrap();
    assert_eq!(team.actions(), favourite + 1);
    team.set_match_seed(1);
    team
}

/// The shipped team's action count (the paper's five).
fn five_outputs(dir: &Path) -> usize {
    let cfg = PlayConfig::read(&dir.join("config.json")).unwrap();
    naosoccer_policy::actions::action_count(cfg.decision())
}

/// Blue 1 at (-1, 0) facing +x with the ball at its feet; blue 2 at `mate`;
/// everybody else out of the way.
fn staged(mate: (f32, f32)) -> Match {
    let mut m = Match::new(&MatchConfig::default(), 3).unwrap();
    for i in 0..ROBOTS {
        let x = -2.4 + 0.6 * (i % 4) as f32 + if i < 4 { 0.0 } else { 0.3 };
        let y = if i < 4 { 2.8 } else { -2.8 };
        m.sim_mut().place_robot(i, x, y, 0.0);
    }
    m.sim_mut().place_robot(1, -1.0, 0.0, 0.0);
    m.sim_mut().place_robot(2, mate.0, mate.1, PI);
    m.sim_mut().place_ball(-0.82, 0.0);
    m.step(&[Action::Stay; ROBOTS]);
    m
}

#[test]
fn pass_is_chosen_only_where_the_observation_allows_it() {
    let mut team = pass_loving_team();
    // A receiver 2 m ahead: the pass.
    let m = staged((1.2, 0.2));
    let obs = m.observe(Team::Blue, 1);
    assert_eq!(naosoccer_proto::pass_receiver(&obs), Some(2));
    assert_eq!(team.act(&obs), Action::Pass);
    // Probabilities with every mask: all on pass.
    let p = team.probabilities_for(std::slice::from_ref(&obs));
    assert!(p[PASS] > 0.999, "{p:?}");
    // The receiver behind the kicker: no pass possible, so not chosen.
    let mut team = pass_loving_team();
    let m = staged((-2.5, 0.0));
    let obs = m.observe(Team::Blue, 1);
    assert_eq!(naosoccer_proto::pass_receiver(&obs), None);
    assert_ne!(team.act(&obs), Action::Pass);
    let p = team.probabilities_for(std::slice::from_ref(&obs));
    assert!(p[PASS] < 1e-6, "{p:?}");
    // A robot far from the ball with a teammate in front: out of reach.
    let mut team = pass_loving_team();
    let m = staged((1.2, 0.2));
    let obs = m.observe(Team::Blue, 0);
    assert_ne!(team.act(&obs), Action::Pass);
}

/// A robot that always chooses `support` walks from behind the kicker to
/// its support spot and turns to the ball, where the protocol's pass rule
/// names it as the receiver; the steps are ordinary protocol actions.
#[test]
fn support_walks_a_robot_to_where_a_pass_reaches_it() {
    let mut team = loving_team(SUPPORT);
    let mut m = staged((-2.0, 1.5));
    let kicker = m.observe(Team::Blue, 1);
    assert_eq!(naosoccer_proto::pass_receiver(&kicker), None);
    let mut seen = Vec::new();
    let mut joint = [Action::Stay; ROBOTS];
    for _ in 0..600 {
        let obs = m.observe(Team::Blue, 2);
        joint[2] = team.act(&obs);
        assert!(
            matches!(
                joint[2],
                Action::Forward | Action::TurnLeft | Action::TurnRight | Action::Stay
            ),
            "support is walking, turning and standing: {:?}",
            joint[2]
        );
        seen.push(joint[2]);
        m.step(&joint);
    }
    assert!(seen.contains(&Action::Forward), "it walked");
    // On its spot (1.5 m ahead of the ball, 1 m to the side), facing the ball.
    let me = m.observe(Team::Blue, 2);
    let r = me.me();
    let ball = (me.ball.x, me.ball.y);
    let (sx, sy) = (ball.0 + 1.5, ball.1 + 1.0);
    assert!(
        (r.x - sx).hypot(r.y - sy) < 0.45,
        "at ({}, {}), spot ({sx}, {sy})",
        r.x,
        r.y
    );
    assert_eq!(joint[2], Action::Stay, "arrived, it stands");
    let kicker = m.observe(Team::Blue, 1);
    assert_eq!(naosoccer_proto::pass_receiver(&kicker), Some(2));
}
