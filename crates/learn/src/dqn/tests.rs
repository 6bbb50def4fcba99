use super::*;
use crate::config::DqnPreset;

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
    let net = QNet::with_input(OBS_DIM, &DqnConfig::default().hidden, "q0");
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
    assert_eq!(
        epsilon_greedy(&q, true, 0.0, &mut rng),
        NetAction::Shoot.index()
    );
    assert_eq!(epsilon_greedy(&q, false, 0.0, &mut rng), 1);
    let mut seen = [0usize; ACTIONS];
    for _ in 0..2000 {
        seen[epsilon_greedy(&q, false, 1.0, &mut rng)] += 1;
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
        seen[epsilon_greedy(&q, true, 1.0, &mut rng)] += 1;
    }
    assert!(seen.iter().all(|&c| c > 300), "{seen:?}");
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
