use super::*;
use naosoccer_policy::Policy;
use naosoccer_proto::Action;
use naosoccer_referee::blank_observation;

fn spec(matches: usize, opponent: &str, minutes: f32) -> EnvSpec {
    let config = MatchConfig {
        minutes,
        ..MatchConfig::default()
    };
    EnvSpec {
        matches,
        controlled: Controlled::Team(Team::Blue),
        opponent: Some(opponent.into()),
        config,
        obs_version: 2,
        decision: None,
        threads: 2,
        scenarios: Vec::new(),
        scenario_weights: None,
        restart: true,
    }
}

#[test]
fn a_slot_plays_the_runners_match_and_restarts() {
    let mut env = VecMatches::new(spec(3, "scripted", 0.1)).unwrap();
    let out = env.reset(40).unwrap();
    assert_eq!(out.obs.len(), 3 * 4 * env.obs_dim());
    let stay = vec![4i64; 12];
    let mut finished = Vec::new();
    while finished.is_empty() {
        let out = env.step(&stay).unwrap();
        finished = out.finished;
    }
    assert_eq!(finished.len(), 3, "equal matches end on the same tick");
    // The runner's match: blue idle (always `stay`), red scripted.
    for f in &finished {
        let m = Match::new(&spec(1, "", 0.1).config, f.seed).unwrap();
        let policies = RobotId::all()
            .map(|r| match r.team() {
                Team::Blue => naosoccer_policy::PolicyKind::Idle.build(f.seed, r),
                Team::Red => naosoccer_policy::PolicyKind::Scripted.build(f.seed, r),
            })
            .collect::<Vec<_>>();
        let hash = play(m, policies);
        assert_eq!(f.state_hash, hash, "slot {}", f.slot);
    }
    assert_eq!(env.seeds(), vec![43, 44, 45]);
    assert_eq!(env.ticks(), vec![0, 0, 0]);
}

fn play(mut m: Match, mut policies: Vec<Box<dyn Policy>>) -> u64 {
    let mut obs: Vec<Observation> = (0..ROBOTS).map(|_| blank_observation()).collect();
    let mut actions = [Action::Stay; ROBOTS];
    while !m.is_finished() {
        for r in RobotId::all() {
            m.observe_into(r.team(), r.player(), &mut obs[r.index()]);
            actions[r.index()] = policies[r.index()].act(&obs[r.index()]);
        }
        m.step(&actions);
    }
    m.state_hash()
}

/// Without restarts a finished match stays as it ended (the PettingZoo
/// env draws and inspects it) and stepping is refused until a reset.
#[test]
fn without_restarts_a_finished_match_stays() {
    let mut s = spec(1, "scripted", 0.1);
    s.restart = false;
    let mut env = VecMatches::new(s).unwrap();
    env.reset(40).unwrap();
    let stay = vec![4i64; 4];
    let finished = loop {
        let out = env.step(&stay).unwrap();
        if !out.finished.is_empty() {
            assert_eq!(out.terminated, [true]);
            break out.finished;
        }
    };
    assert_eq!(finished[0].seed, 40);
    let (over, hash) = env
        .with_match(0, |m| (m.is_finished(), m.state_hash()))
        .unwrap();
    assert!(over);
    assert_eq!(hash, finished[0].state_hash);
    assert_eq!(env.seeds(), vec![40]);
    assert!(matches!(
        env.step(&stay),
        Err(VecEnvError::Ended { slot: 0 })
    ));
    env.reset(41).unwrap();
    assert_eq!(env.ticks(), vec![0]);
    env.step(&stay).unwrap();
    let mut state = Vec::new();
    env.write_states(&mut state);
    assert_eq!(state.len(), crate::state::STATE_DIM);
}

#[test]
fn masks_follow_the_decision_config() {
    let mut s = spec(1, "idle", 0.1);
    s.decision =
        Some(serde_json::from_str(r#"{"persist": 1, "mask_shoot": true, "pass": true}"#).unwrap());
    let mut env = VecMatches::new(s).unwrap();
    assert_eq!(env.actions(), 6);
    let out = env.reset(1).unwrap();
    // At kick-off nobody has the ball in reach: no shoot, no pass.
    for row in out.masks.chunks(6) {
        assert_eq!(row, [true, true, true, false, true, false]);
    }
}

/// A scenario's match ends with its play: the match `naosoccer match
/// --scenario FILE --own red` plays, then the slot restarts from the
/// scenario with its next seed.
#[test]
fn a_scenario_match_ends_with_its_play_and_restarts() {
    let text = "duration = 3.0\n[ball]\nx = 2.5\ny = 0.0\nvx = 2.0\n\
                [[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = 1\n\
                [[end]]\nwhen = \"goal_for\"\noutcome = \"success\"\n";
    let scenario = Scenario::from_toml(text, None).unwrap();
    let mut s = spec(2, "idle", 1.0);
    s.controlled = Controlled::Team(Team::Red);
    s.scenarios = vec![scenario.clone()];
    let cfg = s.config.clone();
    let mut env = VecMatches::new(s).unwrap();
    env.reset(9).unwrap();
    let stay = vec![4i64; 8];
    let mut finished = Vec::new();
    while finished.is_empty() {
        finished = env.step(&stay).unwrap().finished;
    }
    assert_eq!(finished.len(), 2);
    for f in &finished {
        let mut m = Match::with_scenario(&cfg, f.seed, &scenario, Team::Red).unwrap();
        let judge = scenario.judge(&cfg, Team::Red, m.tick());
        let ending = loop {
            let events = m.step(&[Action::Stay; ROBOTS]).to_vec();
            if let Some(e) = judge.check(&m, &events) {
                break e;
            }
        };
        assert_eq!(f.state_hash, m.state_hash(), "slot {}", f.slot);
        assert_eq!(f.score.red, 1, "red, the own team, scored");
        assert_eq!(
            f.scenario,
            Some(ScenarioEnding {
                name: "scenario".into(),
                ending: "goal_for",
                success: true,
                ticks: ending.ticks
            })
        );
    }
    assert_eq!(env.seeds(), vec![11, 12]);
    assert_eq!(env.ticks(), vec![0, 0]);
    // A scenario that does not fit the configuration is refused.
    let mut bad = spec(1, "idle", 1.0);
    bad.scenarios = vec![Scenario::from_toml("[ball]\nx = 4.0\ny = 0\n", None).unwrap()];
    let e = VecMatches::new(bad).err().unwrap().to_string();
    assert!(e.contains("`ball.x`"), "{e}");
}

/// A short scenario (its play lasts half a second: 5 ticks) named
/// `name`, the ball `x` m from the centre, the opponents `opponent`.
fn drill(name: &str, x: f32, opponent: &str) -> Scenario {
    let text = format!(
        "name = \"{name}\"\nopponent = \"{opponent}\"\nduration = 0.5\n\
         [ball]\nx = {x}\ny = [-0.5, 0.5]\n\
         [[robot]]\nside = \"own\"\nplayer = 1\nx = 0\ny = [0.5, 1.5]\n"
    );
    Scenario::from_toml(&text, None).unwrap()
}

fn drills_spec(matches: usize, scenarios: Vec<Scenario>, weights: Option<Vec<f64>>) -> EnvSpec {
    let mut s = spec(matches, "idle", 1.0);
    s.scenarios = scenarios;
    s.scenario_weights = weights;
    s
}

/// The scenario a one-slot env's match of `seed` starts from.
fn drawn(scenarios: &[Scenario], weights: Option<Vec<f64>>, seed: u64) -> usize {
    let mut env = VecMatches::new(drills_spec(1, scenarios.to_vec(), weights)).unwrap();
    env.reset(seed).unwrap();
    env.scenario_indices()[0].unwrap()
}

/// With a list every match start draws its scenario from its seed: the
/// same in any slot, at a reset or a restart, with any threads; both
/// are drawn; each start is the one the scenario draws alone; the
/// finished match names its scenario.
#[test]
fn a_list_draws_a_scenario_per_match_start() {
    let list = vec![drill("near", 2.0, "idle"), drill("far", -2.0, "idle")];
    let cfg = spec(1, "idle", 1.0).config;
    // The start a match of `seed` made from scenario `d` alone.
    let start = |seed, d: usize| {
        Match::with_scenario(&cfg, seed, &list[d], Team::Blue)
            .unwrap()
            .state_hash()
    };
    let mut runs = Vec::new();
    for threads in [1, 3] {
        let mut s = drills_spec(3, list.clone(), None);
        s.threads = threads;
        let mut env = VecMatches::new(s).unwrap();
        assert_eq!(env.opponent(), Some("idle"));
        // (seed, scenario) of every match start, in order.
        let mut starts = Vec::new();
        for reset in [100u64, 200, 300, 400] {
            env.reset(reset).unwrap();
            let indices = env.scenario_indices();
            for ((seed, hash), d) in env.seeds().into_iter().zip(env.state_hashes()).zip(indices) {
                let d = d.unwrap();
                assert_eq!(d, drawn(&list, None, seed), "seed {seed}");
                assert_eq!(hash, start(seed, d), "seed {seed}");
                starts.push((seed, d));
            }
            let mut finished = 0;
            for _ in 0..12 {
                let before = env.scenario_indices();
                let out = env.step(&[4; 12]).unwrap();
                for f in &out.finished {
                    let ending = f.scenario.as_ref().unwrap();
                    assert_eq!(ending.name, list[before[f.slot].unwrap()].name);
                    assert_eq!(ending.ending, "time_up");
                    finished += 1;
                    // The restart drew again, from the slot's next seed.
                    let seed = env.seeds()[f.slot];
                    assert_eq!(seed, f.seed + 3);
                    let d = env.scenario_indices()[f.slot].unwrap();
                    assert_eq!(d, drawn(&list, None, seed), "restart, seed {seed}");
                    assert_eq!(env.state_hashes()[f.slot], start(seed, d));
                    starts.push((seed, d));
                }
            }
            assert_eq!(finished, 6, "every slot's first two matches ended");
        }
        for d in [0, 1] {
            assert!(starts.iter().any(|s| s.1 == d), "{d} drawn: {starts:?}");
        }
        runs.push(starts);
    }
    assert_eq!(runs[0], runs[1], "the same with 1 and 3 threads");
}

/// A list of one plays as its scenario alone, bit for bit, whatever
/// its weight; so does a list whose other scenarios weigh 0.
#[test]
fn a_list_of_one_is_the_scenario_alone() {
    let one = drill("one", 1.0, "scripted");
    let other = drill("other", -1.0, "scripted");
    let run = |scenarios: Vec<Scenario>, weights: Option<Vec<f64>>| {
        let mut s = drills_spec(2, scenarios, weights);
        s.opponent = None;
        let mut env = VecMatches::new(s).unwrap();
        assert_eq!(env.opponent(), Some("scripted"));
        env.reset(5).unwrap();
        let mut hashes = vec![env.state_hashes()];
        for _ in 0..12 {
            let out = env.step(&[0, 1, 3, 4, 4, 3, 1, 0]).unwrap();
            hashes.push(env.state_hashes());
            hashes.push(out.finished.iter().map(|f| f.state_hash).collect());
        }
        hashes
    };
    let alone = run(vec![one.clone()], None);
    let cfg = spec(1, "idle", 1.0).config;
    let start = |seed| {
        Match::with_scenario(&cfg, seed, &one, Team::Blue)
            .unwrap()
            .state_hash()
    };
    assert_eq!(alone[0], vec![start(5), start(6)]);
    assert_eq!(run(vec![one.clone()], Some(vec![3.5])), alone);
    assert_eq!(
        run(vec![one.clone(), other.clone()], Some(vec![1.0, 0.0])),
        alone
    );
    assert_eq!(run(vec![other, one], Some(vec![0.0, 2.0])), alone);
}

/// The weights set the chances; a scenario of weight 0 is never drawn.
#[test]
fn weights_set_the_chances() {
    let list = vec![
        drill("a", 1.0, "idle"),
        drill("b", 0.0, "idle"),
        drill("c", -1.0, "idle"),
    ];
    let mut env = VecMatches::new(drills_spec(50, list, Some(vec![3.0, 0.0, 1.0]))).unwrap();
    let mut counts = [0usize; 3];
    for reset in 0..20 {
        env.reset(reset * 1000).unwrap();
        for d in env.scenario_indices() {
            counts[d.unwrap()] += 1;
        }
    }
    assert_eq!(counts[1], 0, "{counts:?}");
    // 1000 draws of chance 3/4: 750 +- 14 (one standard deviation).
    assert!((690..=810).contains(&counts[0]), "{counts:?}");
}

/// Bad weights, entries that do not fit and opponents that cannot be
/// told apart per match are refused, naming what is wrong.
#[test]
fn bad_lists_are_refused() {
    let two = || vec![drill("a", 1.0, "idle"), drill("b", -1.0, "scripted")];
    let error = |scenarios: Vec<Scenario>, weights: Option<Vec<f64>>| {
        VecMatches::new(drills_spec(1, scenarios, weights))
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default()
    };
    for (weights, says) in [
        (vec![1.0], "1 given for 2 scenarios"),
        (vec![1.0, 2.0, 3.0], "3 given for 2 scenarios"),
        (vec![1.0, -1.0], "weight 1 is -1"),
        (vec![f64::NAN, 1.0], "weight 0 is NaN"),
        (vec![f64::INFINITY, 1.0], "weight 0 is inf"),
        (vec![0.0, 0.0], "all are 0"),
        (vec![f64::MAX, f64::MAX], "sum is not a finite number"),
    ] {
        let e = error(two(), Some(weights));
        assert!(
            e.starts_with("scenario_weights: ") && e.contains(says),
            "{e}"
        );
    }
    let e = error(Vec::new(), Some(vec![1.0]));
    assert_eq!(e, "scenario_weights: given without a scenario");
    let far = Scenario::from_toml("name = \"far\"\n[ball]\nx = 4.0\ny = 0\n", None).unwrap();
    let e = error(vec![drill("a", 1.0, "idle"), far], None);
    assert!(
        e.starts_with("scenario[1] (far): ") && e.contains("`ball.x`"),
        "{e}"
    );
    // Different built-in opponents: each match plays its scenario's.
    let mut s = drills_spec(1, two(), None);
    s.opponent = None;
    let env = VecMatches::new(s).unwrap();
    assert_eq!(env.opponent(), Some(PER_SCENARIO));
    // A trained team among them needs `opponent=`.
    let mut s = drills_spec(
        1,
        vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
        None,
    );
    s.opponent = None;
    let e = VecMatches::new(s).err().unwrap().to_string();
    assert!(
        e.contains("scenario[1] (t)") && e.contains("pass opponent="),
        "{e}"
    );
    // Named, it plays every match; the scenarios' own are not read.
    let mut s = drills_spec(
        1,
        vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
        None,
    );
    s.opponent = Some("random".into());
    assert_eq!(VecMatches::new(s).unwrap().opponent(), Some("random"));
    // Self-play has no opponents to choose.
    let mut s = drills_spec(
        1,
        vec![drill("a", 1.0, "idle"), drill("t", 0.0, "ppo:nowhere")],
        None,
    );
    s.opponent = None;
    s.controlled = Controlled::Both;
    assert_eq!(VecMatches::new(s).unwrap().opponent(), None);
}

/// With opponents per scenario each match plays its own scenario's: the
/// match of an env of that scenario alone, opponents and all.
#[test]
fn each_match_plays_its_scenarios_opponents() {
    let list = vec![
        drill("idle", 1.0, "idle"),
        drill("scripted", 1.0, "scripted"),
    ];
    let mut s = drills_spec(6, list.clone(), None);
    s.opponent = None;
    let mut env = VecMatches::new(s).unwrap();
    env.reset(64).unwrap();
    for _ in 0..4 {
        env.step(&[4; 24]).unwrap();
    }
    let indices = env.scenario_indices();
    assert!(
        indices.contains(&Some(0)) && indices.contains(&Some(1)),
        "{indices:?}"
    );
    for (i, d) in indices.into_iter().enumerate() {
        let d = d.unwrap();
        let mut s = drills_spec(1, vec![list[d].clone()], None);
        s.opponent = None;
        let mut alone = VecMatches::new(s).unwrap();
        assert_eq!(alone.opponent(), Some(list[d].opponent.as_str()));
        alone.reset(64 + i as u64).unwrap();
        for _ in 0..4 {
            alone.step(&[4; 4]).unwrap();
        }
        assert_eq!(env.state_hashes()[i], alone.state_hashes()[0], "slot {i}");
    }
}

#[test]
fn bad_actions_are_refused() {
    let mut env = VecMatches::new(spec(2, "random", 0.1)).unwrap();
    env.reset(0).unwrap();
    assert!(matches!(
        env.step(&[0; 7]),
        Err(VecEnvError::ActionCount {
            expected: 8,
            got: 7
        })
    ));
    let mut a = [0i64; 8];
    a[5] = 5;
    assert!(matches!(
        env.step(&a),
        Err(VecEnvError::Action { robot: 5, .. })
    ));
}

/// Everything a run of steps returns, bits and all.
fn trace(threads: usize, steps: usize) -> Vec<String> {
    let mut s = spec(5, "scripted", 0.2);
    s.threads = threads;
    s.decision = Some(serde_json::from_str(r#"{"mask_shoot": true, "pass": true}"#).unwrap());
    let mut env = VecMatches::new(s).unwrap();
    assert_eq!(env.threads(), threads.min(5));
    let out = env.reset(7).unwrap();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut trace = vec![format!("{:?} {:?}", bits(&out.obs), out.masks)];
    // A fixed stream of valid actions (xorshift), the same for every run.
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..steps {
        let actions: Vec<i64> = (0..20)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x % 6) as i64
            })
            .collect();
        let out = env.step(&actions).unwrap();
        trace.push(format!(
            "{:?} {:?} {:?} {:?} {:?}",
            bits(&out.obs),
            bits(&out.rewards),
            out.terminated,
            out.masks,
            out.finished
                .iter()
                .map(|f| (f.slot, f.seed, f.ticks, f.state_hash, bits(&f.obs)))
                .collect::<Vec<_>>()
        ));
        trace.push(format!("{:x?}", env.state_hashes()));
    }
    trace
}

/// The matches are the same, tick for tick and bit for bit, whatever the
/// number of threads stepping them (five slots: shares that do not
/// divide evenly; 300 steps: every slot's first match ends at 120 and
/// its second at 240).
#[test]
fn threads_do_not_change_the_matches() {
    let one = trace(1, 300);
    assert!(one.iter().any(|t| t.contains("true")), "matches ended");
    for threads in [2, 3, 8] {
        let other = trace(threads, 300);
        let first = one.iter().zip(&other).position(|(a, b)| a != b);
        assert_eq!(
            first, None,
            "threads {threads}: the first entry that differs"
        );
    }
}

/// A policy that meets its twin of the other slot at a barrier before
/// acting, so that the two slots are stepped at once, by two threads;
/// the one that panics records which thread it ran on.
struct Twin {
    barrier: Arc<std::sync::Barrier>,
    panics: Option<Arc<std::sync::Mutex<Option<String>>>>,
}

impl Policy for Twin {
    fn act(&mut self, _: &Observation) -> Action {
        self.barrier.wait();
        if let Some(thread) = &self.panics {
            *thread.lock().unwrap() = std::thread::current().name().map(String::from);
            panic!("a robot's policy failed");
        }
        Action::Stay
    }

    fn name(&self) -> &str {
        "twin"
    }
}

/// A panic on a stepping thread comes back as an error (not a hang, not
/// a panic of the caller); stepping is refused until the next reset,
/// which plays on with the same threads.
#[test]
fn a_panic_on_a_worker_is_an_error() {
    let mut env = VecMatches::new(spec(2, "idle", 0.1)).unwrap();
    env.reset(3).unwrap();
    let barrier = Arc::new(std::sync::Barrier::new(2));
    let thread = Arc::new(std::sync::Mutex::new(None));
    {
        assert_eq!(env.stepper.as_ref().unwrap().threads(), 2);
        // The caller takes slot 0 first and waits at the barrier for
        // slot 1, which only the worker can then be stepping.
        let red0 = RobotId::new(Team::Red, 0).unwrap();
        env.slots[0].game.set_policy(
            red0,
            Some(Box::new(Twin {
                barrier: Arc::clone(&barrier),
                panics: None,
            })),
        );
        env.slots[1].game.set_policy(
            red0,
            Some(Box::new(Twin {
                barrier,
                panics: Some(Arc::clone(&thread)),
            })),
        );
    }
    let stay = [4i64; 8];
    let e = env.step(&stay).err().unwrap();
    assert!(
        matches!(&e, VecEnvError::Panicked(m) if m == "a robot's policy failed"),
        "{e}"
    );
    let name = thread.lock().unwrap().clone();
    assert!(
        name.as_deref()
            .is_some_and(|n| n.starts_with("naosoccer-step-")),
        "the panic was on a stepping thread, not {name:?}"
    );
    assert!(matches!(env.step(&stay), Err(VecEnvError::Panicked(_))));
    env.reset(3).unwrap();
    env.step(&stay).unwrap();
    assert_eq!(env.ticks(), vec![1, 1]);
}
