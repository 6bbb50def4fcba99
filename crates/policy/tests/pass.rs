//! A team with the `pass` action plays it only where the observation says a
//! pass is possible (ball in kick reach, a receiver named by the protocol's
//! pass rule), in process exactly as over the socket; a team with the
//! `support` action walks to where a pass can reach it, and one with roles
//! leaves walking and turning to its chasers.

use std::f32::consts::PI;
use std::path::Path;

use naosoccer_policy::Policy;
use naosoccer_policy::{LearnedPolicy, NetAction, PlayConfig, Weights};
use naosoccer_proto::{Action, Team, ROBOTS};
use naosoccer_referee::{Match, MatchConfig};

/// The shipped seed-1 team given a sixth output whose bias makes `pass`
/// the greedy choice wherever it is allowed.
fn pass_loving_team() -> LearnedPolicy {
    loving_team(NetAction::Pass.index())
}

/// The shipped seed-1 team given outputs up to `favourite` (`pass`, or
/// `pass` and `support`), the last with a bias that makes it the greedy
/// choice wherever it is allowed.
fn loving_team(favourite: usize) -> LearnedPolicy {
    team_loving(favourite, favourite, 0)
}

/// The shipped seed-1 team given outputs up to `last` (`pass`, or `pass`
/// and `support`), with `chasers` as given and a bias that makes
/// `favourite` the greedy choice wherever it is allowed.
fn team_loving(last: usize, favourite: usize, chasers: u32) -> LearnedPolicy {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/policies/ppo-team-v3-seed1");
    let mut cfg = PlayConfig::read(&dir.join("config.json")).unwrap();
    let d = cfg.ppo.decision.as_mut().unwrap();
    d.pass = true;
    d.support = last == NetAction::Support.index();
    d.chasers = chasers;
    let extra = last + 1 - five_outputs(&dir);
    let five = Weights::read(&dir.join("final.safetensors")).unwrap();
    let mut w = Weights::default();
    let out = five
        .names()
        .filter(|n| n.starts_with("actor.") && n.ends_with(".bias"))
        .max()
        .unwrap()
        .trim_end_matches(".bias")
        .to_string();
    for name in five.names() {
        let (shape, data) = five.get(name).unwrap();
        let (mut shape, mut data) = (shape.to_vec(), data.to_vec());
        if name == format!("{out}.weight") {
            data.extend(std::iter::repeat_n(0.0, shape[1] * extra));
            shape[0] += extra;
        } else if name == format!("{out}.bias") {
            data.extend(std::iter::repeat_n(0.0, extra));
            data[favourite] += 1e3;
            shape[0] += extra;
        }
        w.insert(name, shape, data);
    }
    let mut team = LearnedPolicy::from_weights(&cfg, &w, "loving".into()).unwrap();
    assert_eq!(team.actions(), last + 1);
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
    assert!(p[NetAction::Pass.index()] > 0.999, "{p:?}");
    // The receiver behind the kicker: no pass possible, so not chosen.
    let mut team = pass_loving_team();
    let m = staged((-2.5, 0.0));
    let obs = m.observe(Team::Blue, 1);
    assert_eq!(naosoccer_proto::pass_receiver(&obs), None);
    assert_ne!(team.act(&obs), Action::Pass);
    let p = team.probabilities_for(std::slice::from_ref(&obs));
    assert!(p[NetAction::Pass.index()] < 1e-6, "{p:?}");
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
    let mut team = loving_team(NetAction::Support.index());
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

/// With one chaser only the standing robot nearest the ball (on a tie the
/// lower player number) may walk `forward` or turn: a team that loves
/// `forward` walks its chaser and sends the others to `support` or `stay`,
/// whoever asks, and a fallen robot hands the chase on. With two, the two
/// nearest chase; with `support_only` the others may not `stay` either.
#[test]
fn roles_leave_walking_and_turning_to_the_chasers() {
    use naosoccer_policy::actions::{banned_actions, is_chaser, ROLE_BANNED, SUPPORT_ONLY_BANNED};
    let mut team = team_loving(NetAction::Support.index(), 0, 1);
    // Blue 1 has the ball at its feet; blue 2 stands 1.9 m from it.
    let m = staged((-2.0, 1.5));
    let chaser = m.observe(Team::Blue, 1);
    assert!(is_chaser(&chaser, 1));
    assert_eq!(team.act(&chaser), Action::Forward);
    let p = team.probabilities_for(std::slice::from_ref(&chaser));
    assert!(p[0] > 0.999, "{p:?}");
    let mut other = m.observe(Team::Blue, 2);
    assert!(!is_chaser(&other, 1));
    // Blue 2 is the second nearest: with two chasers it chases, blue 0 not.
    assert!(is_chaser(&other, 2));
    assert!(!is_chaser(&m.observe(Team::Blue, 0), 2));
    let p = team.probabilities_for(std::slice::from_ref(&other));
    assert!(p[..3].iter().all(|&x| x < 1e-6), "{p:?}");
    assert!((p[NetAction::Support.index()..].iter().sum::<f32>() + p[4] - 1.0).abs() < 1e-4);
    let d = team.decision().unwrap();
    let in_reach = false;
    assert_eq!(
        banned_actions(&other, in_reach, &d),
        ROLE_BANNED | NetAction::Pass.bit()
    );
    // With support only it may not stay either.
    let mut strict = d;
    strict.support_only = true;
    assert_eq!(
        banned_actions(&other, in_reach, &strict),
        SUPPORT_ONLY_BANNED | NetAction::Pass.bit()
    );
    assert_eq!(
        banned_actions(&chaser, true, &strict) & SUPPORT_ONLY_BANNED,
        0
    );
    // Without roles the same robot may walk.
    let mut free = d;
    free.chasers = 0;
    assert_eq!(
        banned_actions(&other, in_reach, &free),
        NetAction::Pass.bit()
    );
    // The chaser falls: blue 2, the nearest standing robot, chases.
    other.own[1].fallen = true;
    assert!(is_chaser(&other, 1));
    // A tie goes to the lower player number.
    other.own[3] = other.own[2];
    assert!(is_chaser(&other, 1));
    other.player = naosoccer_proto::Player::new(3).unwrap();
    assert!(!is_chaser(&other, 1));
    assert!(is_chaser(&other, 2));
    // A lying robot never chases.
    let mut lying = m.observe(Team::Blue, 1);
    lying.own[1].fallen = true;
    assert!(!is_chaser(&lying, 3));
}
