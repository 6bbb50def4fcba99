//! Probes a trained team on the states it meets in play: it plays matches as
//! blue against an opponent and, at every tick a robot of it decides (free,
//! standing), sorts the situation into a few kinds and sums the action the
//! robot took. Unlike `probe` (states built by hand) nothing here is off the
//! team's own state distribution.
//!
//! It also says what became of the team's kicks (a pass, the kicker's own
//! control again, an opponent's, a goal, the ball out) and how long the
//! passes among them were, for all kicks and for those decided with a
//! teammate open in line (a pass attempt).
//!
//! The team may also be a built-in one (`scripted`, `scripted:FILE.toml`),
//! to compare with the hand-written team's passing.
//!
//! With `force` after MATCHES, every free robot of the team that has the
//! ball in reach and a teammate open in line shoots, whatever its policy
//! says: what passing there would bring.
//!
//! `cargo run --release -p naosoccer-learn --example probe_play -- ppo:DIR|scripted [OPPONENT] [MATCHES] [force]`

use naosoccer_learn::obs::{ball_in_robot_frame, ObsScale};
use naosoccer_learn::policy::is_free;
use naosoccer_learn::LearnedPolicy;
use naosoccer_policy::actions::ACTION_NAMES;
use naosoccer_policy::{Policy, PolicyKind};
use naosoccer_proto::{Action, Event, Observation, RobotId, Team, PLAYERS_PER_TEAM, ROBOTS};
use naosoccer_referee::rules::segment_distance;
use naosoccer_referee::{Match, MatchConfig};

/// The team probed: a trained one, or a built-in one robot by robot.
enum Blue {
    Learned(Box<LearnedPolicy>),
    Builtin(PolicyKind, Vec<Box<dyn Policy>>),
}

const OUTCOMES: [&str; 6] = [
    "a pass",
    "the kicker's control",
    "an opponent's control",
    "a goal",
    "the ball out",
    "another kick first",
];
const KINDS: [&str; 7] = [
    "ball in kick reach, facing the opponent half",
    "ball in kick reach, facing the own half",
    "ball within 1 m, ahead (+-20 deg), out of reach",
    "ball ahead (+-20 deg), farther than 1 m",
    "ball to the left (20-135 deg)",
    "ball to the right (20-135 deg)",
    "ball behind (>135 deg)",
];

fn kind(o: &Observation, in_reach: bool) -> usize {
    let me = o.me();
    let (ahead, side) = ball_in_robot_frame(o);
    let bearing = side.atan2(ahead).to_degrees();
    let d = ahead.hypot(side);
    if in_reach {
        return if me.heading.cos() >= 0.0 { 0 } else { 1 };
    }
    if bearing.abs() <= 20.0 {
        if d <= 1.0 {
            2
        } else {
            3
        }
    } else if bearing.abs() > 135.0 {
        6
    } else if bearing > 0.0 {
        4
    } else {
        5
    }
}

/// Whether a teammate of the robot that received `o` stands where a kick
/// now would reach it: 1-3 m ahead, within 15 degrees of the heading, with no
/// standing opponent within 0.3 m of the line from the ball to it.
fn pass_on(o: &Observation) -> bool {
    let me = o.me();
    let (s, c) = me.heading.sin_cos();
    let mine = o.player.index();
    o.own.iter().enumerate().any(|(p, m)| {
        if p == mine || m.fallen {
            return false;
        }
        let (dx, dy) = (m.x - me.x, m.y - me.y);
        let (ahead, side) = (c * dx + s * dy, -s * dx + c * dy);
        let d = ahead.hypot(side);
        let open = o
            .opponents
            .iter()
            .filter(|q| !q.fallen)
            .all(|q| segment_distance([o.ball.x, o.ball.y], [m.x, m.y], [q.x, q.y]) > 0.3);
        (1.0..=3.0).contains(&d) && side.atan2(ahead).abs() <= 15f32.to_radians() && open
    })
}

/// For the robot that received `o` with the ball in reach: whether some
/// standing teammate is 1-4 m away within 15, 30 and 45 degrees of its heading.
fn mate_cones(o: &Observation) -> [bool; 3] {
    let me = o.me();
    let (s, c) = me.heading.sin_cos();
    let mine = o.player.index();
    let mut hit = [false; 3];
    for (p, m) in o.own.iter().enumerate() {
        if p == mine || m.fallen {
            continue;
        }
        let (dx, dy) = (m.x - me.x, m.y - me.y);
        let (ahead, side) = (c * dx + s * dy, -s * dx + c * dy);
        if !(1.0..=4.0).contains(&ahead.hypot(side)) {
            continue;
        }
        let bearing = side.atan2(ahead).abs().to_degrees();
        for (k, limit) in [15.0, 30.0, 45.0].into_iter().enumerate() {
            hit[k] |= bearing <= limit;
        }
    }
    hit
}

/// Bearing bins (degrees off the heading, either side) and distance bins
/// (metres) of the teammates around a robot with the ball in reach.
const BEARINGS: [f32; 5] = [15.0, 45.0, 90.0, 135.0, 180.0];
const DISTANCES: [f32; 4] = [1.0, 2.0, 4.0, f32::INFINITY];

/// For the robot that received `o` with the ball in reach: adds each
/// standing teammate to its (bearing, distance) bin.
fn mate_bins(o: &Observation, bins: &mut [[u64; DISTANCES.len()]; BEARINGS.len()]) {
    let me = o.me();
    let (s, c) = me.heading.sin_cos();
    let mine = o.player.index();
    for (p, m) in o.own.iter().enumerate() {
        if p == mine || m.fallen {
            continue;
        }
        let (dx, dy) = (m.x - me.x, m.y - me.y);
        let (ahead, side) = (c * dx + s * dy, -s * dx + c * dy);
        let bearing = side.atan2(ahead).abs().to_degrees();
        let d = ahead.hypot(side);
        let b = BEARINGS.iter().position(|&l| bearing <= l).unwrap_or(4);
        let k = DISTANCES.iter().position(|&l| d <= l).unwrap_or(3);
        bins[b][k] += 1;
    }
}

/// The ticks counted in `row` and each action's share of them, as text.
fn action_shares(row: &[u64; ACTION_NAMES.len()]) -> (u64, String) {
    let n: u64 = row.iter().sum();
    let shares: Vec<String> = row
        .iter()
        .zip(ACTION_NAMES)
        .map(|(c, name)| format!("{name} {:.2}", *c as f64 / n.max(1) as f64))
        .collect();
    (n, shares.join(", "))
}

fn main() {
    let mut args = std::env::args().skip(1);
    let spec = args
        .next()
        .expect("usage: probe_play ppo:DIR|scripted [OPPONENT] [MATCHES]");
    let opponent = args.next().unwrap_or_else(|| "scripted".into());
    let matches: u64 = args.next().map_or(4, |m| m.parse().expect("MATCHES"));
    let force = match args.next().as_deref() {
        None => false,
        Some("force") => true,
        Some(other) => panic!("expected `force` after MATCHES, got {other:?}"),
    };
    let opp: PolicyKind = opponent.parse().expect("a built-in opponent");
    let cfg = MatchConfig::default();
    let mut team = match spec.parse::<PolicyKind>() {
        Ok(kind) => Blue::Builtin(kind, Vec::new()),
        Err(_) => Blue::Learned(Box::new(
            LearnedPolicy::load(&spec).expect("load the policy"),
        )),
    };
    let reach = match &team {
        Blue::Learned(t) => t.scale().kick,
        Blue::Builtin(..) => ObsScale::from_config(&cfg).kick,
    };
    let mut counts = [[0u64; ACTION_NAMES.len()]; KINDS.len()];
    // Ball in kick reach with a teammate open where the kick would go.
    let mut pass_counts = [0u64; ACTION_NAMES.len()];
    let (mut reach_ticks, mut cone_ticks) = (0u64, [0u64; 3]);
    // In-reach ticks by the third of the pitch the ball is in (own, middle,
    // opponents'), and of those how many the kicker faced its own half.
    let mut thirds = [[0u64; 2]; 3];
    let third_length = cfg.sim.field_length / 3.0;
    let mut bins = [[0u64; DISTANCES.len()]; BEARINGS.len()];
    // What became of blue's kicks: the first of a pass, the kicker's own
    // control again, an opponent's control, a goal, the ball out.
    let mut kick_outcomes = [0u64; OUTCOMES.len()];
    // The same for the kicks decided with a teammate open in line
    // (`pass_on`), and whether each robot's last shoot was decided so.
    let mut aimed_outcomes = [0u64; OUTCOMES.len()];
    let mut aimed_at = [false; PLAYERS_PER_TEAM];
    let mut pending_aimed = false;
    // Lengths of the passes that settled a kick: under 1 m, 1-2 m, 2 m on.
    let mut pass_lengths = [0u64; 3];
    // The pending kick's kicker, and whether the ball has left its control
    // since (right after the kick it may still be within reach).
    let mut pending: Option<RobotId> = None;
    let mut left = false;
    let (mut stat_passes, mut stat_shots) = (0u64, 0u64);
    for seed in 0..matches {
        let mut m = Match::new(&cfg, 1_000_000 + seed).expect("a match");
        match &mut team {
            Blue::Learned(t) => t.set_match_seed(m.seed()),
            Blue::Builtin(kind, robots) => {
                *robots = (0..PLAYERS_PER_TEAM)
                    .map(|i| kind.build(m.seed(), RobotId::from_index(i).unwrap()))
                    .collect();
            }
        }
        let mut reds: Vec<Box<dyn Policy>> = (PLAYERS_PER_TEAM..ROBOTS)
            .map(|i| opp.build(m.seed(), RobotId::from_index(i).unwrap()))
            .collect();
        while !m.is_finished() {
            let blue: Vec<Observation> = (0..PLAYERS_PER_TEAM)
                .map(|p| m.observe(Team::Blue, p))
                .collect();
            let mut acts = [Action::Stay; ROBOTS];
            // The team's choices (a learned team's `support` is counted as
            // such; what it walks with goes in `acts`).
            let mut chosen = [0usize; PLAYERS_PER_TEAM];
            match &mut team {
                Blue::Learned(t) => {
                    t.act_matches(&[(m.seed(), &blue)], &mut chosen);
                    for (p, o) in blue.iter().enumerate() {
                        acts[p] = t.action(chosen[p], o);
                    }
                }
                Blue::Builtin(_, robots) => {
                    for ((a, r), o) in acts.iter_mut().zip(robots.iter_mut()).zip(&blue) {
                        *a = r.act(o);
                    }
                    for (c, a) in chosen.iter_mut().zip(&acts) {
                        *c = a.index();
                    }
                }
            }
            for (p, o) in blue.iter().enumerate() {
                // Free robots only: a lying or kicking robot's action does
                // nothing. A movement held for a few ticks counts each tick.
                if is_free(o) {
                    let in_reach = reach.in_reach(o);
                    counts[kind(o, in_reach)][chosen[p]] += 1;
                    let open = in_reach && pass_on(o);
                    if open && force {
                        acts[p] = Action::Shoot;
                        chosen[p] = Action::Shoot.index();
                    }
                    if open {
                        pass_counts[chosen[p]] += 1;
                    }
                    if matches!(acts[p], Action::Shoot | Action::Pass) {
                        aimed_at[p] = open;
                    }
                    if in_reach {
                        reach_ticks += 1;
                        let third = ((o.ball.x / third_length + 1.5).floor() as usize).min(2);
                        thirds[third][0] += 1;
                        thirds[third][1] += u64::from(o.me().heading.cos() < 0.0);
                        for (t, h) in cone_ticks.iter_mut().zip(mate_cones(o)) {
                            *t += u64::from(h);
                        }
                        mate_bins(o, &mut bins);
                    }
                }
            }
            for (i, red) in reds.iter_mut().enumerate() {
                let o = m.observe(Team::Red, i);
                acts[PLAYERS_PER_TEAM + i] = red.act(&o);
            }
            let events = m.step(&acts).to_vec();
            // In order: a kick opens, a pass, goal or out settles (a pass may
            // come in the kick's own tick, to a teammate at the ball).
            for e in &events {
                let settled = match *e {
                    Event::Kick { robot, .. } => {
                        if pending.is_some() {
                            kick_outcomes[5] += 1;
                            aimed_outcomes[5] += u64::from(pending_aimed);
                        }
                        pending = (robot.team() == Team::Blue).then_some(robot);
                        pending_aimed = pending.is_some() && aimed_at[robot.player()];
                        left = false;
                        None
                    }
                    Event::Pass { from, distance, .. } if Some(from) == pending => {
                        pass_lengths
                            [usize::from(distance >= 1.0) + usize::from(distance >= 2.0)] += 1;
                        Some(0)
                    }
                    Event::Goal { .. } => Some(3),
                    Event::BallOut { .. } => Some(4),
                    _ => None,
                };
                if let (Some(k), true) = (settled, pending.is_some()) {
                    kick_outcomes[k] += 1;
                    aimed_outcomes[k] += u64::from(pending_aimed);
                    pending = None;
                }
            }
            if pending.is_some() {
                let settled = match m.controller() {
                    Some(c) if Some(c) == pending => left.then_some(1),
                    Some(c) if c.team() == Team::Blue => Some(0),
                    Some(_) => Some(2),
                    None => {
                        left = true;
                        None
                    }
                };
                if let Some(k) = settled {
                    kick_outcomes[k] += 1;
                    aimed_outcomes[k] += u64::from(pending_aimed);
                    pending = None;
                }
            }
        }
        pending = None;
        let st = m.stats();
        stat_passes += u64::from(st.team(Team::Blue).passes);
        stat_shots += u64::from(st.team(Team::Blue).shots);
    }
    let forced = if force {
        " (forced to shoot with a teammate open in line)"
    } else {
        ""
    };
    println!(
        "{spec} as blue against {opponent}, {matches} matches{forced}: actions taken by free robots"
    );
    let tally = |counts: &[u64; OUTCOMES.len()]| -> (u64, String) {
        let text: Vec<String> = counts
            .iter()
            .zip(OUTCOMES)
            .map(|(c, name)| format!("{name} {c}"))
            .collect();
        (counts.iter().sum(), text.join(", "))
    };
    let (kicks, outcomes) = tally(&kick_outcomes);
    println!(
        "  blue's {kicks} kicks ended in: {outcomes} (the statistics: {stat_passes} passes, {stat_shots} shots)"
    );
    let (aimed, outcomes) = tally(&aimed_outcomes);
    println!("  {aimed} of them decided with a teammate open 1-3 m ahead (+-15 deg) ended in: {outcomes}");
    println!(
        "  of those passes, {} were shorter than 1 m, {} 1-2 m and {} longer",
        pass_lengths[0], pass_lengths[1], pass_lengths[2]
    );
    for (k, row) in counts.iter().enumerate() {
        let (n, shares) = action_shares(row);
        println!("  {} ({n} ticks): {shares}", KINDS[k]);
    }
    let (n, shares) = action_shares(&pass_counts);
    println!("  ball in kick reach, a teammate open 1-3 m ahead (+-15 deg) ({n} ticks): {shares}");
    let share = |k: usize| cone_ticks[k] as f64 / reach_ticks.max(1) as f64;
    println!(
        "  of {reach_ticks} ticks with the ball in reach, a standing teammate 1-4 m away within \
         15 / 30 / 45 deg of the heading: {:.2} / {:.2} / {:.2}",
        share(0),
        share(1),
        share(2)
    );
    let cells: Vec<String> = thirds
        .iter()
        .map(|[n, back]| format!("{n} ({:.2})", *back as f64 / (*n).max(1) as f64))
        .collect();
    println!(
        "  ticks with the ball in reach in the own / middle / opponents' third of the pitch \
         (in brackets, the share facing the own half): {}",
        cells.join(" / ")
    );
    let total: u64 = bins.iter().flatten().sum();
    println!(
        "  where the standing teammates are then (share of {total} teammate-ticks), by degrees off \
         the heading (rows) and metres away (columns <=1, 1-2, 2-4, >4):"
    );
    let mut lo = 0.0;
    for (b, row) in BEARINGS.iter().zip(bins) {
        let cells: Vec<String> = row
            .iter()
            .map(|&c| format!("{:.2}", c as f64 / total.max(1) as f64))
            .collect();
        println!("    {lo:>3}-{b:<3} deg: {}", cells.join("  "));
        lo = *b;
    }
}
