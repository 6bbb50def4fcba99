//! Probes a trained team on the pass drills (assets/scenarios/training/
//! pass-*.toml, played for 10 s each as `env::ScenarioDrills`): the ball at a
//! learner's feet, a teammate open ahead in its line, the opponents of a
//! built-in team coming. For each 10-second drill it says what came first:
//! a teammate's control (a pass, to the receiver placed in line or to
//! another), an opponent's, a goal, or nothing (the kicker kept the ball or
//! nobody controlled it); and how often the kicker's first decision was to
//! shoot.
//!
//! `cargo run --release -p naosoccer-learn --example probe_drill -- ppo:DIR [OPPONENT] [DRILLS] [SEED]`

use naosoccer_learn::env::{EnvConfig, Opponent, ScenarioDrills, ScenarioText, VecEnv};
use naosoccer_learn::LearnedPolicy;
use naosoccer_policy::obs::ObsScale;
use naosoccer_policy::PolicyKind;
use naosoccer_proto::Observation;
use naosoccer_referee::MatchConfig;

const OUTCOMES: [&str; 5] = [
    "a pass to the receiver in line",
    "a pass to another teammate",
    "an opponent's control",
    "a goal",
    "none in 10 s",
];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = args
        .first()
        .expect("usage: probe_drill ppo:DIR [OPPONENT] [DRILLS] [SEED]");
    let opponent: PolicyKind = args
        .get(1)
        .map_or("scripted", String::as_str)
        .parse()
        .expect("opponent: a built-in team");
    let drills: usize = args.get(2).map_or(400, |s| s.parse().expect("DRILLS"));
    let seed: u64 = args.get(3).map_or(11, |s| s.parse().expect("SEED"));
    // The receiver's largest angle off the kicker's heading in the drills.
    let angle: f32 = 0.17;
    let cfg = MatchConfig::default();
    let scale = ObsScale::from_config(&cfg);
    let matches = 16;
    let mut env = VecEnv::new(
        &cfg,
        EnvConfig {
            matches,
            learners: vec![0, 1, 2, 3],
            teammates: PolicyKind::Idle,
            threads: 2,
            seed,
            support_spot: Default::default(),
        },
        Opponent::Builtin(opponent),
    )
    .expect("environment");
    let root =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenarios/training");
    let scenarios = (0..4)
        .map(|k| {
            let mut s =
                ScenarioText::read(&root.join(format!("pass-{k}.toml"))).expect("pass drill");
            s.text = s.text.replace("duration = 30.0", "duration = 10.0");
            s
        })
        .collect();
    env.set_scenarios(Some(&ScenarioDrills { matches, scenarios }))
        .expect("drills");
    let mut team = LearnedPolicy::load(spec).expect("team");
    let rows = env.rows();
    let mut actions = vec![0usize; rows];
    // Per match: the kicker, the receiver placed in line, the outcome so far,
    // whether the kicker has decided yet.
    let mut state: Vec<(usize, Option<usize>, Option<usize>, bool)> =
        vec![(0, None, None, false); matches];
    let mut counts = [0usize; OUTCOMES.len()];
    let mut first_shoot = 0usize;
    let mut done = 0usize;
    let start = |o: &[&Observation]| -> (usize, Option<usize>, Option<usize>, bool) {
        let k = (0..4).find(|&p| scale.kick.in_reach(o[p])).unwrap_or(0);
        let me = o[0].own[k];
        let (bx, by) = (o[0].ball.x, o[0].ball.y);
        let recv = (0..4).filter(|&p| p != k).find(|&p| {
            let r = o[0].own[p];
            let d = (r.x - bx).hypot(r.y - by);
            let off = ((r.y - by).atan2(r.x - bx) - me.heading + std::f32::consts::PI)
                .rem_euclid(std::f32::consts::TAU)
                - std::f32::consts::PI;
            (1.0..=2.7).contains(&d) && off.abs() < angle + 0.15
        });
        (k, recv, None, false)
    };
    let obs_of = |env: &VecEnv, m: usize| -> Vec<Observation> {
        (0..4)
            .map(|p| env.learner_observation(m * 4 + p).clone())
            .collect()
    };
    for (m, s) in state.iter_mut().enumerate() {
        let o = obs_of(&env, m);
        *s = start(&o.iter().collect::<Vec<_>>());
    }
    while done < drills {
        let all: Vec<Vec<Observation>> = (0..matches).map(|m| obs_of(&env, m)).collect();
        let teams: Vec<(u64, &[Observation])> = all
            .iter()
            .enumerate()
            .map(|(m, o)| (seed * 1000 + m as u64, o.as_slice()))
            .collect();
        team.act_matches(&teams, &mut actions);
        for (m, s) in state.iter_mut().enumerate() {
            if !s.3 && !all[m][s.0].me().busy {
                s.3 = true;
                first_shoot += usize::from(actions[m * 4 + s.0] == 3);
            }
        }
        let score: Vec<_> = all.iter().map(|o| o[0].score).collect();
        env.step(&actions).expect("step");
        for (m, s) in state.iter_mut().enumerate() {
            let o = obs_of(&env, m);
            if env.dones()[m * 4] {
                counts[s.2.unwrap_or(4)] += 1;
                done += 1;
                *s = start(&o.iter().collect::<Vec<_>>());
                continue;
            }
            if s.2.is_some() {
                continue;
            }
            if o[0].score != score[m] {
                s.2 = Some(3);
            } else if o[0].opponent_control {
                s.2 = Some(2);
            } else if let Some(p) = (0..4).find(|&p| o[0].control[p] && p != s.0) {
                s.2 = Some(if Some(p) == s.1 { 0 } else { 1 });
            }
        }
    }
    println!("{spec} against {opponent}: {done} pass drills of 10 s, seed {seed}");
    for (name, c) in OUTCOMES.iter().zip(counts) {
        println!(
            "  first: {name:<32} {:>5.1}%",
            100.0 * c as f64 / done as f64
        );
    }
    println!(
        "  the kicker's first decision was to shoot: {:.1}%",
        100.0 * first_shoot as f64 / done as f64
    );
}
