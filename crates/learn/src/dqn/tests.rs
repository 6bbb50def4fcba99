use super::*;
use crate::config::DqnPreset;
use naosoccer_policy::actions::{NetAction, ACTIONS};

#[test]
fn td_target_is_reward_plus_discounted_max_unless_done() {
    let r = Tensor::from_slice(&[1.0f32, 0.5, -1.0]);
    let q = Tensor::from_slice(&[
        0.0f32, 2.0, 1.0, 0.0, 0.0, -1.0, -3.0, -2.0, -5.0, -4.0, 10.0, 0.0, 0.0, 0.0, 0.0,
    ])
    .view([3, 5]);
    let d = Tensor::from_slice(&[0.0f32, 0.0, 1.0]);
    let y = td_target(&r, &q, &d, 0.9);
    let mut v = [0.0f32; 3];
    y.copy_data(&mut v, 3);
    // 1 + 0.9 * 2; 0.5 + 0.9 * (-1); terminal: the reward alone.
    let expected = [2.8, 0.5 - 0.9, -1.0];
    for (a, b) in v.iter().zip(expected) {
        assert!((a - b).abs() < 1e-6, "{v:?} vs {expected:?}");
    }
}

#[test]
fn the_q_network_has_five_linear_layers() {
    let net = QNet::with_input(OBS_DIM, &DqnConfig::default().hidden, ACTIONS, "q0");
    let mut names: Vec<String> = net
        .vs
        .variables()
        .into_keys()
        .filter(|k| k.ends_with("weight"))
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "q0.l0.weight",
            "q0.l1.weight",
            "q0.l2.weight",
            "q0.l3.weight",
            "q0.l4.weight"
        ]
    );
}

fn values(t: &Tensor) -> Vec<f32> {
    let n = t.numel();
    let mut v = vec![0.0f32; n];
    t.copy_data(&mut v, n);
    v
}

#[test]
fn the_paper_target_is_the_discounted_target_with_gamma_until_done() {
    let r = Tensor::from_slice(&[1.0f32, 0.5, -1.0]);
    let q = Tensor::from_slice(&[
        0.0f32, 2.0, 1.0, 0.0, 0.0, -1.0, -3.0, -2.0, -5.0, -4.0, 10.0, 0.0, 0.0, 0.0, 0.0,
    ])
    .view([3, 5]);
    let d = Tensor::from_slice(&[0.0f32, 0.0, 1.0]);
    let g = Tensor::from_slice(&[0.99f32, 0.99, 0.0]);
    assert_eq!(
        values(&td_target(&r, &q, &d, 0.99)),
        values(&td_target_discounted(&r, &g, &q, None, None))
    );
}

#[test]
fn double_dqn_values_the_online_choice_with_the_target_network() {
    let r = Tensor::from_slice(&[1.0f32, 0.0, 2.0]);
    // Per-transition discounts: gamma^dt for dt = 1, 3 and a finished episode.
    let g = Tensor::from_slice(&[0.9f32, 0.729, 0.0]);
    let target = Tensor::from_slice(&[
        5.0f32, 1.0, 0.0, 0.0, 0.0, // max 5 at action 0
        0.0, 0.0, 7.0, 2.0, 0.0, // max 7 at action 2
        9.0, 9.0, 9.0, 9.0, 9.0,
    ])
    .view([3, 5]);
    let online = Tensor::from_slice(&[
        0.0f32, 3.0, 0.0, 0.0, 0.0, // picks action 1
        0.0, 0.0, 0.0, 4.0, 0.0, // picks action 3
        1.0, 0.0, 0.0, 0.0, 0.0,
    ])
    .view([3, 5]);
    let y = values(&td_target_discounted(&r, &g, &target, Some(&online), None));
    // Double: target's value of the online argmax, not the target's max.
    let expected = [1.0 + 0.9 * 1.0, 0.729 * 2.0, 2.0];
    for (a, b) in y.iter().zip(expected) {
        assert!((a - b).abs() < 1e-6, "{y:?} vs {expected:?}");
    }
    let plain = values(&td_target_discounted(&r, &g, &target, None, None));
    let expected = [1.0 + 0.9 * 5.0, 0.729 * 7.0, 2.0];
    for (a, b) in plain.iter().zip(expected) {
        assert!((a - b).abs() < 1e-6, "{plain:?} vs {expected:?}");
    }
}

#[test]
fn masked_next_actions_are_neither_chosen_nor_valued() {
    let r = Tensor::from_slice(&[0.0f32, 0.0]);
    let g = Tensor::from_slice(&[1.0f32, 1.0]);
    // Shoot (index 3) is the best next action of both rows, by both nets.
    let q = Tensor::from_slice(&[
        1.0f32, 0.0, 0.0, 9.0, 0.0, //
        0.0, 2.0, 0.0, 9.0, 0.0,
    ])
    .view([2, 5]);
    // Row 0: the ball is out of reach in s'; row 1: in reach.
    let mut m = vec![0.0f32; 10];
    m[NetAction::Shoot.index()] = MASKED_Q;
    let mask = Tensor::from_slice(&m).view([2, 5]);
    assert_eq!(
        values(&td_target_discounted(&r, &g, &q, Some(&q), Some(&mask))),
        [1.0, 9.0]
    );
    assert_eq!(
        values(&td_target_discounted(&r, &g, &q, None, Some(&mask))),
        [1.0, 9.0]
    );
    // A finished episode bootstraps nothing, masked or not.
    let done = Tensor::from_slice(&[0.0f32, 0.0]);
    assert_eq!(
        values(&td_target_discounted(&r, &done, &q, None, Some(&mask))),
        [0.0, 0.0]
    );
}

#[test]
fn epsilon_greedy_never_picks_a_masked_shoot() {
    use rand::SeedableRng;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let q = [0.0f32, 1.0, 0.0, 5.0, 0.0];
    let (ok, out) = (
        allowed_actions(true, 0, ACTIONS),
        allowed_actions(false, 0, ACTIONS),
    );
    assert_eq!(
        epsilon_greedy(&q, ok, 0.0, &mut rng),
        NetAction::Shoot.index()
    );
    assert_eq!(epsilon_greedy(&q, out, 0.0, &mut rng), 1);
    let mut seen = [0usize; ACTIONS];
    for _ in 0..2000 {
        seen[epsilon_greedy(&q, out, 1.0, &mut rng)] += 1;
    }
    assert_eq!(seen[NetAction::Shoot.index()], 0, "{seen:?}");
    assert!(
        seen.iter()
            .enumerate()
            .all(|(i, &c)| i == NetAction::Shoot.index() || c > 400),
        "{seen:?}"
    );
    let mut seen = [0usize; ACTIONS];
    for _ in 0..2000 {
        seen[epsilon_greedy(&q, ok, 1.0, &mut rng)] += 1;
    }
    assert!(seen.iter().all(|&c| c > 300), "{seen:?}");
}

/// The five-action choice as it was before DQN's team preset had more
/// actions: a `shoot_ok` flag, the random draw skipping a masked `shoot`,
/// the greedy one starting from `forward`.
fn epsilon_greedy_five(q: &[f32], shoot_ok: bool, epsilon: f64, rng: &mut ChaCha8Rng) -> usize {
    let shoot = NetAction::Shoot.index();
    if rng.random::<f64>() < epsilon {
        let a = rng.random_range(0..ACTIONS - usize::from(!shoot_ok));
        return if !shoot_ok && a >= shoot { a + 1 } else { a };
    }
    let mut best = 0;
    for (i, &x) in q.iter().enumerate() {
        if (i != shoot || shoot_ok) && x > q[best] {
            best = i;
        }
    }
    best
}

/// A five-action team whose only mask is `shoot`'s acts bit for bit as
/// before: the same choices and the same draws from the generator (the
/// pinned DQN run depends on it).
#[test]
fn five_actions_choose_and_draw_as_before() {
    use rand::SeedableRng;
    let (mut a, mut b) = (ChaCha8Rng::seed_from_u64(9), ChaCha8Rng::seed_from_u64(9));
    let mut q = [0.0f32; ACTIONS];
    for i in 0..20_000 {
        for (j, v) in q.iter_mut().enumerate() {
            // Ties (0.0) and a varying best, shoot among them.
            *v = ((i * 7 + j * 3) % 5) as f32 - 2.0;
        }
        let ok = i % 3 != 0;
        let eps = [0.0, 0.3, 1.0][i % 3];
        let new = epsilon_greedy(&q, allowed_actions(ok, 0, ACTIONS), eps, &mut a);
        assert_eq!(new, epsilon_greedy_five(&q, ok, eps, &mut b), "draw {i}");
    }
    assert_eq!(a.random::<u64>(), b.random::<u64>(), "the same stream");
}

/// With more actions and bans (roles, `pass` without a receiver, a masked
/// `shoot`): never a banned action, every allowed one drawn, and greedy is
/// the best allowed one even where a banned one (`forward`, the first)
/// values more.
#[test]
fn epsilon_greedy_keeps_to_the_allowed_actions() {
    use naosoccer_policy::actions::ROLE_BANNED;
    use rand::SeedableRng;
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let k = 9;
    let q = [9.0f32, 8.0, 7.0, 6.0, 1.0, 5.0, 2.0, 4.0, 3.0];
    let bans = ROLE_BANNED | NetAction::Pass.bit() | NetAction::Approach.bit();
    let allowed = allowed_actions(false, bans, k);
    let expect = [NetAction::Stay, NetAction::Support, NetAction::Defend];
    assert_eq!(
        allowed,
        expect.iter().fold(0, |s, a| s | a.bit()),
        "stay, support, defend"
    );
    assert_eq!(
        epsilon_greedy(&q, allowed, 0.0, &mut rng),
        NetAction::Defend.index()
    );
    let mut seen = [0usize; 9];
    for _ in 0..3000 {
        seen[epsilon_greedy(&q, allowed, 1.0, &mut rng)] += 1;
    }
    for (i, &c) in seen.iter().enumerate() {
        if allowed & (1 << i) != 0 {
            assert!(c > 800, "{i} drawn {c} times of 3000: {seen:?}");
        } else {
            assert_eq!(c, 0, "banned {i} drawn: {seen:?}");
        }
    }
    // Half random: still never banned.
    for _ in 0..2000 {
        let a = epsilon_greedy(&q, allowed, 0.5, &mut rng);
        assert!(allowed & (1 << a) != 0, "{a}");
    }
}

/// The target's max (and Double DQN's online argmax) run over the next
/// state's allowed actions only, as the replay masks them: a banned next
/// action with the largest value is neither chosen nor valued.
#[test]
fn the_target_ignores_banned_next_actions() {
    use rand::SeedableRng;
    let k = 9;
    let mut replay = Replay::new(4, k);
    let o = [0.0f32; OBS_DIM];
    // Row 0: support and defend only; row 1: everything but forward.
    let only = NetAction::Support.bit() | NetAction::Defend.bit();
    let not_forward = all_actions(k) & !NetAction::Forward.bit();
    replay.push(&o, 0, 0.0, &o, 1.0, only);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (_, _, _, _, _, mask) = replay.sample(1, &mut rng);
    assert_eq!(mask.size(), [1, k as i64]);
    let m = values(&mask);
    for (a, &x) in m.iter().enumerate() {
        let allowed = only & (1 << a) != 0;
        assert_eq!(x, if allowed { 0.0 } else { MASKED_Q }, "{a}: {m:?}");
    }
    let mut rows = m;
    let mut second = vec![0.0f32; k];
    second[NetAction::Forward.index()] = MASKED_Q;
    assert_eq!(allowed_actions(true, !not_forward, k), not_forward);
    rows.extend(second);
    let mask = Tensor::from_slice(&rows).view([2, k as i64]);
    // Forward (banned in both rows) values most; then pass (banned in
    // row 0), then defend.
    let q = Tensor::from_slice(&[
        10.0f32, 0.0, 0.0, 0.0, 0.0, 8.0, 1.0, 0.0, 3.0, //
        10.0, 0.0, 0.0, 0.0, 0.0, 8.0, 1.0, 0.0, 3.0,
    ])
    .view([2, k as i64]);
    let r = Tensor::from_slice(&[0.0f32, 0.0]);
    let g = Tensor::from_slice(&[1.0f32, 1.0]);
    assert_eq!(
        values(&td_target_discounted(&r, &g, &q, None, Some(&mask))),
        [3.0, 8.0]
    );
    // Double DQN: the online network prefers approach (banned in row 0)
    // and support; the target values the choice.
    let online = Tensor::from_slice(&[
        0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0, 9.0, 0.0, //
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0, 9.0, 0.0,
    ])
    .view([2, k as i64]);
    assert_eq!(
        values(&td_target_discounted(
            &r,
            &g,
            &q,
            Some(&online),
            Some(&mask)
        )),
        [1.0, 0.0]
    );
}

/// Without masks (the paper, an episode's end) the replay's mask is all
/// zeros, as the five-action buffer's was.
#[test]
fn an_unmasked_next_state_masks_nothing() {
    use rand::SeedableRng;
    let mut replay = Replay::new(2, ACTIONS);
    let o = [0.0f32; OBS_DIM];
    replay.push(&o, 1, 1.0, &o, 0.0, all_actions(ACTIONS));
    replay.push(&o, 2, 1.0, &o, 0.5, allowed_actions(false, 0, ACTIONS));
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let (_, a, _, _, _, mask) = replay.sample(64, &mut rng);
    let (a, m) = (values(&a.to_kind(Kind::Float)), values(&mask));
    for (i, &act) in a.iter().enumerate() {
        let mut want = [0.0f32; ACTIONS];
        if act == 2.0 {
            want[NetAction::Shoot.index()] = MASKED_Q;
        }
        assert_eq!(m[i * ACTIONS..(i + 1) * ACTIONS], want);
    }
}

/// `Dqn::q_values` hands out each row's network outputs, one per action of
/// the decision settings, with one shared network and with one per robot.
#[test]
fn q_values_are_the_networks_outputs_for_every_action() {
    let _ = tch::no_grad_guard();
    for (shared, pass) in [(true, false), (true, true), (false, true)] {
        let mut cfg = DqnConfig::team();
        cfg.shared = shared;
        cfg.hidden = vec![8];
        let d = cfg.decision.as_mut().unwrap();
        if pass {
            (d.pass, d.support, d.defend) = (true, true, true);
        }
        let k = cfg.actions();
        assert_eq!(k, if pass { 9 } else { ACTIONS });
        let robots = 2;
        let mut dqn = Dqn::new(cfg, robots, OBS_DIM).unwrap();
        let n = 4;
        let obs: Vec<f32> = (0..n * OBS_DIM).map(|i| (i % 7) as f32 * 0.1).collect();
        let mut q = Vec::new();
        dqn.q_values(&obs, robots, &mut q);
        assert_eq!(q.len(), n * k);
        for i in 0..n {
            let x = Tensor::from_slice(&obs[i * OBS_DIM..(i + 1) * OBS_DIM]).view([1, -1]);
            let want = values(&dqn.nets[dqn.net_of(i % robots)].q(&x));
            // (A batch of one rounds a little differently.)
            let got = &q[i * k..(i + 1) * k];
            let close = got.iter().zip(&want).all(|(a, b)| (a - b).abs() < 1e-5);
            assert!(close, "row {i}, shared {shared}: {got:?} vs {want:?}");
        }
        assert!(q.iter().any(|&v| v != 0.0));
    }
}

#[test]
fn epsilon_falls_linearly_then_stays() {
    let mut c = DqnConfig::team();
    c.epsilon_start = 1.0;
    c.epsilon = 0.1;
    c.epsilon_decay = 1000;
    assert_eq!(c.epsilon_at(0), 1.0);
    assert!((c.epsilon_at(500) - 0.55).abs() < 1e-12);
    assert!((c.epsilon_at(900) - 0.19).abs() < 1e-12);
    assert_eq!(c.epsilon_at(1000), 0.1);
    assert_eq!(c.epsilon_at(10_000_000), 0.1);
    // The paper's is fixed.
    let p = DqnConfig::paper();
    assert_eq!((p.epsilon_at(0), p.epsilon_at(5_000_000)), (0.3, 0.3));
    assert!((DqnConfig::team().discount(3) - 0.995f32.powi(3)).abs() < 1e-7);
}

#[test]
fn configurations_without_the_new_fields_load_as_the_paper() {
    // A DQN section as the shipped dqn-seed* runs wrote it.
    let old = r#"{"gamma":0.99,"lr":0.001,"epsilon":0.3,"hidden":[128,128,128,128],
        "replay":100000,"batch":128,"warmup":1000,"target_every":1000,
        "updates_per_step":1,"shared":false}"#;
    let c: DqnConfig = serde_json::from_str(old).unwrap();
    assert_eq!(c, DqnConfig::paper());
    assert_eq!("team".parse::<DqnPreset>(), Ok(DqnPreset::Team));
    assert!("rainbow".parse::<DqnPreset>().is_err());
}

#[test]
fn argmax_takes_the_first_of_ties() {
    assert_eq!(argmax(&[0.0, 3.0, 3.0, -1.0]), 1);
}

#[test]
fn polyak_moves_the_average_toward_the_network_by_one_minus_keep() {
    let net = QNet::with_input(OBS_DIM, &[4], 3, "q0");
    let avg = QNet::with_input(OBS_DIM, &[4], 3, "q0");
    let (a0, n0) = (avg.vs.trainable_variables(), net.vs.trainable_variables());
    let before: Vec<Vec<f32>> = a0.iter().map(|t| values(&t.flatten(0, -1))).collect();
    let online: Vec<Vec<f32>> = n0.iter().map(|t| values(&t.flatten(0, -1))).collect();
    polyak(&avg.vs, &net.vs, 0.75);
    let after = avg.vs.trainable_variables();
    assert_eq!(after.len(), before.len());
    for ((t, b), o) in after.iter().zip(&before).zip(&online) {
        for ((x, b), o) in values(&t.flatten(0, -1)).iter().zip(b).zip(o) {
            assert!((x - (0.75 * b + 0.25 * o)).abs() < 1e-6, "{x} vs {b}, {o}");
        }
    }
    // The network it follows is left alone.
    let still: Vec<Vec<f32>> = net
        .vs
        .trainable_variables()
        .iter()
        .map(|t| values(&t.flatten(0, -1)))
        .collect();
    assert_eq!(still, online);
}

#[test]
fn an_average_outside_zero_to_one_is_refused() {
    for bad in [-0.1, 1.0, 2.0, f64::NAN] {
        let mut cfg = DqnConfig::team();
        cfg.hidden = vec![8];
        cfg.average = bad;
        assert!(Dqn::new(cfg, 4, OBS_DIM).is_err(), "{bad}");
    }
    let mut cfg = DqnConfig::team();
    cfg.hidden = vec![8];
    cfg.average = 0.999;
    let dqn = Dqn::new(cfg, 4, OBS_DIM).unwrap();
    assert!(dqn.averaging());
    assert!(!Dqn::new(DqnConfig::team(), 4, OBS_DIM).unwrap().averaging());
}
