use super::*;
use crate::obs::OBS_DIM;
use rand::SeedableRng;

fn vals(t: &Tensor) -> Vec<f32> {
    let n = t.numel();
    let mut v = vec![0.0; n];
    t.to_kind(Kind::Float).copy_data(&mut v, n);
    v
}

#[test]
fn surrogate_clips_the_ratio_on_the_side_the_advantage_favours() {
    // ratios e^0.5 = 1.65, e^-0.5 = 0.61, 1.0 and 1.1 with advantages +1, -1, +2, -1.
    let logp_old = Tensor::from_slice(&[0.0f32, 0.0, 0.0, 0.0]);
    let logp = Tensor::from_slice(&[0.5f32, -0.5, 0.0, 1.1f32.ln()]);
    let adv = Tensor::from_slice(&[1.0f32, -1.0, 2.0, -1.0]);
    let loss = vals(&clipped_surrogate_loss(&logp, &logp_old, &adv, 0.2))[0];
    // min(1.65*1, 1.2*1) = 1.2; min(0.61*-1, 0.8*-1) = -0.8; 2.0; min(-1.1, -1.1) = -1.1.
    let expected = -(1.2 - 0.8 + 2.0 - 1.1) / 4.0;
    assert!((loss - expected).abs() < 1e-5, "{loss} vs {expected}");
}

#[test]
fn surrogate_gradient_vanishes_once_clipped() {
    let logp = Tensor::from_slice(&[0.5f32]).set_requires_grad(true);
    let loss = clipped_surrogate_loss(
        &logp,
        &Tensor::from_slice(&[0.0f32]),
        &Tensor::from_slice(&[1.0f32]),
        0.2,
    );
    loss.backward();
    assert_eq!(vals(&logp.grad()), vec![0.0]);
    let logp = Tensor::from_slice(&[0.1f32]).set_requires_grad(true);
    let loss = clipped_surrogate_loss(
        &logp,
        &Tensor::from_slice(&[0.0f32]),
        &Tensor::from_slice(&[1.0f32]),
        0.2,
    );
    loss.backward();
    // d(-ratio)/dlogp = -ratio inside the clip range.
    assert!((vals(&logp.grad())[0] + 0.1f32.exp()).abs() < 1e-5);
}

#[test]
fn sampling_follows_the_probabilities() {
    let p = [0.1, 0.2, 0.3, 0.4, 0.0];
    assert_eq!(sample(&p, 0.05), 0);
    assert_eq!(sample(&p, 0.25), 1);
    assert_eq!(sample(&p, 0.59), 2);
    assert_eq!(sample(&p, 0.99), 3);
}

/// Two robots' decisions: stream A decides at ticks 0, 3 (three-tick
/// holds) and is cut by the rollout edge at tick 5; stream B decides at
/// 0 and its episode ends after 7 ticks.
fn two_streams() -> Transitions {
    Transitions {
        obs: Vec::new(),
        critic_obs: Vec::new(),
        actions: vec![0, 0, 1],
        logp: vec![0.0; 3],
        shoot_ok: vec![true; 3],
        banned: vec![],
        // Closing order: A's first (index 0), A's second (1, at the
        // edge), B's (2, at the end).
        values: vec![1.0, 2.0, 0.5],
        rewards: vec![0.3, 0.2, 1.0],
        dt: vec![3, 2, 7],
        next_values: vec![2.0, 4.0, 9.0],
        dones: vec![false, false, true],
        next: vec![Some(1), None, None],
    }
}

#[test]
fn decision_gae_discounts_by_elapsed_ticks() {
    let tr = two_streams();
    let (g, l) = (0.9f32, 0.5f32);
    let (adv, ret) = tr.gae(g, l);
    // A's second: cut at the edge, bootstrapped with V = 4 after 2 ticks.
    let a1 = 0.2 + g.powi(2) * 4.0 - 2.0;
    // A's first: its next decision 3 ticks later has V = 2, and its
    // advantage carries (g l)^3 of the next one's.
    let a0 = 0.3 + g.powi(3) * 2.0 - 1.0 + (g * l).powi(3) * a1;
    // B's: the episode ended; nothing is bootstrapped past it.
    let a2 = 1.0 - 0.5;
    let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
    assert!(
        close(adv[0], a0) && close(adv[1], a1) && close(adv[2], a2),
        "{adv:?}"
    );
    assert!(close(ret[0], a0 + 1.0) && close(ret[2], 1.0));
    // With one-tick steps, decision GAE is the per-tick GAE.
    let per_tick = Transitions {
        dt: vec![1, 1, 1],
        ..two_streams()
    };
    let (adv, _) = per_tick.gae(g, l);
    let t1 = 0.2 + g * 4.0 - 2.0;
    let t0 = 0.3 + g * 2.0 - 1.0 + g * l * t1;
    assert!(close(adv[0], t0) && close(adv[1], t1), "{adv:?}");
}

#[test]
fn the_papers_returns_are_discounted_along_each_robots_stream() {
    // One-tick transitions of two robots, time-major: A at 0, 2, 4; B at
    // 1, 3, 5; B's episode ends after its second, A's stream runs into
    // the rollout's edge.
    let tr = Transitions {
        actions: vec![0; 6],
        rewards: vec![1.0, 0.0, 1.0, 1.0, 1.0, 1.0],
        dt: vec![1; 6],
        dones: vec![false, false, false, true, false, false],
        next: vec![Some(2), Some(3), Some(4), None, None, None],
        ..Transitions::default()
    };
    // A: 1 + 0.5 (1 + 0.5 * 1) = 1.75, 1.5, 1 (no bootstrap at the edge);
    // B: 0 + 0.5 * 1 = 0.5, 1 (its episode ended), 1.
    assert_eq!(
        tr.discounted_returns(0.5),
        vec![1.75, 0.5, 1.5, 1.0, 1.0, 1.0]
    );
}

#[test]
fn running_norm_tracks_mean_and_variance() {
    let mut n = RunningNorm::default();
    n.update(&[1.0, 3.0]);
    n.update(&[5.0, 7.0, 9.0]);
    assert!((n.mean - 5.0).abs() < 1e-3, "{n:?}");
    assert!((n.var - 8.0).abs() < 1e-2, "{n:?}");
    let y = n.normalise(7.0);
    assert!((n.denormalise(y) - 7.0).abs() < 1e-5);
}

#[test]
fn a_masked_shoot_is_never_sampled_and_has_no_probability() {
    tch::manual_seed(0);
    let scale = ObsScale::from_config(&naosoccer_referee::MatchConfig::default());
    let mut ppo = Ppo::new(PpoConfig::team(), &scale, 4).unwrap();
    let n = 64;
    let obs = vec![0.1f32; n * OBS_DIM];
    let ok: Vec<bool> = (0..n).map(|i| i % 2 == 0).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let (mut a, mut lp) = (vec![0; n], vec![0.0; n]);
    let mut shot_when_allowed = 0;
    for _ in 0..20 {
        ppo.act_masked(&obs, &ok, &[], &mut rng, &mut a, &mut lp);
        for i in 0..n {
            if a[i] == NetAction::Shoot.index() {
                assert!(ok[i], "row {i} shot with the ball out of reach");
                shot_when_allowed += 1;
            }
        }
    }
    assert!(
        shot_when_allowed > 0,
        "an untrained policy shoots when it may"
    );
}
