//! `LearnedPolicy::act_rows_keyed` acts on bare observation rows, which
//! carry no bans: whatever `act_matches` decided before on the same policy
//! (with its own masks) leaves no mark on it.

use naosoccer_policy::{LearnedPolicy, OBS_DIM};
use naosoccer_proto::{Observation, RobotId, Team};
use naosoccer_referee::{Match, MatchConfig};

/// The shipped team trained with `pass`, `support` and two chasers: at the
/// kick-off its other robots may not walk `forward` or turn.
const TEAM: &str = concat!(
    "ppo:",
    env!("CARGO_MANIFEST_DIR"),
    "/../../assets/policies/ppo-team-seed1"
);

#[test]
fn rows_acted_on_after_a_match_s_masks_are_not_masked() {
    let m = Match::new(&MatchConfig::default(), 5).unwrap();
    let obs: Vec<Observation> = RobotId::all()
        .filter(|r| r.team() == Team::Blue)
        .map(|r| m.observe(r.team(), r.player()))
        .collect();
    let mut used = LearnedPolicy::load(TEAM).unwrap();
    let mut acts = vec![0usize; obs.len()];
    used.act_matches(&[(5, obs.as_slice())], &mut acts);

    // Uniform draws of 0 sample the first action a row allows: `forward`
    // (0) unless it is masked.
    let rows = vec![0.0f32; obs.len() * OBS_DIM];
    let players = [0, 1, 2, 3];
    let uniforms = [0.0f32; 4];
    let mut after = [9usize; 4];
    used.act_rows_keyed(&rows, &players, &uniforms, &mut after);
    let mut fresh = LearnedPolicy::load(TEAM).unwrap();
    let mut alone = [9usize; 4];
    fresh.act_rows_keyed(&rows, &players, &uniforms, &mut alone);
    assert_eq!(after, alone, "the match's masks were applied to the rows");
    assert_eq!(alone, [0; 4], "an unmasked row's first action is forward");
}
