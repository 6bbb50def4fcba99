//! `naosoccer train | plot` and `bench learn`: the learning crate (tch) on
//! the command line, built with the `train` feature. Wall-clock rates are measured here, at the edge; the
//! library's results never depend on them.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use naosoccer_learn::config::{DqnConfig, DqnPreset};
use naosoccer_learn::config::{PpoConfig, Preset};
use naosoccer_learn::train::{train, Algo, OpponentSpec, TrainConfig};

use super::eval::match_config;

fn parse_players(s: &str) -> Result<Vec<usize>, String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<usize>()
                .map_err(|_| format!("bad player number {p:?}"))
        })
        .collect::<Result<_, _>>()?;
    if v.is_empty() || v.iter().any(|&p| p > 3) {
        return Err(format!("players are 0..=3, got {s:?}"));
    }
    Ok(v)
}

#[derive(Args, Debug)]
#[command(after_help = "Examples:
  naosoccer train --recipe assets/recipes/ppo-team.toml --out runs/ppo-team-1 --seed 1
  naosoccer train --resume runs/ppo-team-1   # go on after a stop, bit for bit
  naosoccer train --algo ppo --preset team --opponent scripted:2 --steps 5000000 --seed 1 \\
                  --out runs/ppo-team-small
  naosoccer train --algo dqn --preset team --steps 3000000 --seed 1 --out runs/dqn-team-1
  naosoccer train --algo ppo --preset cleanrl --opponent self-play:200000 --out runs/ppo-sp
  naosoccer train --algo ppo --steps 2000000 --seed 1 --out runs/ppo-1   # the paper's PPO

Every other setting of a run (the team preset's actions and roles, pass
drills, the observation layout, PPO and DQN hyperparameters, learners and
teammates: 35 in all) is a recipe field and is also accepted here as an
option of the same name (--KEY VALUE, --KEY for a switch); docs/LEARNING.md
lists them in its table of recipe fields.

Presets (--preset, PPO): paper (the paper's Algorithm 2, every robot decides
every tick), cleanrl (GAE, advantage normalisation, grad-norm clipping,
orthogonal init) and team (the decision-level MDP: a robot decides only
when free to act, not lying or in a kick; movement holds for --persist
ticks; shoot is masked while the ball is out of kick reach; returns are
discounted by elapsed time; with value normalisation, a KL early stop,
annealed learning rate and entropy; --central-critic for MAPPO).

The run directory gets config.json (everything the run depends on),
metrics.csv (one row per update), checkpoints/step-N.safetensors and
final.safetensors. Play the result with `naosoccer eval --blue ppo:DIR` or
`naosoccer client --policy ppo:DIR`. See docs/LEARNING.md.")]
pub struct TrainArgs {
    /// Run every stage of a training recipe (a TOML file, e.g.
    /// assets/recipes/ppo-team.toml: each `[[stage]]` is a `train` command
    /// written as fields) into --out with --seed; each stage gets its own
    /// directory, `--resume DIR` continues the chain where it stopped, and
    /// DIR/time.json holds the wall-clock time of the whole chain. The
    /// finished team is `ppo:DIR`. Other options belong in the recipe
    /// (but --threads).
    #[arg(long, value_name = "FILE", conflicts_with_all = [
        "algo", "steps", "resume", "preset", "persist", "no_shoot_mask", "pass_action",
        "support_action", "support_hold", "support_roles", "support_only", "support_spot",
        "approach_action", "approach_only", "defend_action", "give_action", "own_goal_guard", "init_from", "pass_init", "support_init_bias",
        "central_critic", "minibatches", "entropy_coef", "entropy_coef_end", "gamma", "target_kl", "lr", "drill",
        "scenarios", "scenario_matches", "obs_version", "opponent",
        "matches", "torch_threads", "config", "minutes", "learners", "teammates",
        "checkpoint_every", "rollout", "epochs", "shared", "n_step", "epsilon", "average"])]
    recipe: Option<PathBuf>,
    /// Algorithm: dqn (the paper's Algorithm 1) or ppo (Algorithm 2).
    #[arg(long, required_unless_present_any = ["resume", "recipe"])]
    algo: Option<Algo>,
    /// Robot transitions to train for (one learning robot, one control
    /// tick); default 1000000. With --resume: the run's new total length.
    #[arg(long)]
    steps: Option<u64>,
    /// Continue the run in DIR from its latest checkpoint, as if it had not
    /// stopped (team preset; its config.json decides everything else).
    #[arg(long, value_name = "DIR", conflicts_with = "out")]
    resume: Option<PathBuf>,
    /// Seed of the matches, the weights and the sampling.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Run directory to write (created; existing files are overwritten).
    #[arg(long, required_unless_present = "resume")]
    out: Option<PathBuf>,
    /// Hyperparameters. PPO: paper (Algorithm 2, PPO-PyTorch defaults),
    /// cleanrl (GAE, advantage normalisation, grad-norm clipping, orthogonal
    /// init) or team (the decision-level MDP with the PPO fixes). DQN: paper
    /// (Algorithm 1: per-robot networks, fixed epsilon 0.3) or team (Double
    /// DQN, 3-step returns, Huber loss, epsilon 1 -> 0.05 over 1M
    /// transitions, one network for the team, on the decision-level MDP).
    #[arg(long, default_value = "paper")]
    preset: String,
    /// Team presets (PPO and DQN): ticks a movement decision holds.
    #[arg(long, hide = true)]
    persist: Option<u32>,
    /// Team presets: let robots shoot with the ball out of reach.
    #[arg(long, hide = true)]
    no_shoot_mask: bool,
    /// PPO or DQN team preset: give the robots a sixth action, `pass` (a kick
    /// toward the teammate the protocol's pass rule names; see
    /// docs/PROTOCOL.md), possible only with the ball in kick reach and a
    /// teammate to receive it.
    #[arg(long, hide = true)]
    pass_action: bool,
    /// PPO or DQN team preset, with --pass-action: give the robots a seventh
    /// action, `support`, a walk to the support spot 1.5 m ahead of the
    /// ball and 1 m to its side (where a pass can reach them), facing the
    /// ball once there. The team's policy turns it into `forward`, turns
    /// and `stay` each tick, so it needs nothing new on the wire.
    #[arg(long, hide = true, requires = "pass_action")]
    support_action: bool,
    /// PPO or DQN team preset, with --support-action: one `support` decision
    /// holds up to this many ticks (10 ticks = 1 s at the default 10 Hz; a
    /// robot walks 0.2 m/s), until the robot reaches its spot or the ball comes
    /// within 0.6 m of it, instead of --persist ticks like any movement.
    /// Recorded in the run's configuration, so the team plays the same way in
    /// `match`, `eval` and over the socket. 0: off.
    #[arg(long, hide = true, value_name = "TICKS", requires = "support_action")]
    support_hold: Option<u32>,
    /// PPO or DQN team preset, with --support-action: roles. Only the team's
    /// CHASERS (1 to 3) standing robots nearest the ball (on a tie the lower
    /// player number is nearer) may walk `forward` or turn; the others choose
    /// among `support`, `stay` and, with the ball in reach, `shoot` and `pass`.
    /// Read from each robot's own observation and recorded in the run's
    /// configuration, so the team plays the same way in `match`, `eval` and
    /// over the socket.
    #[arg(long, hide = true, value_name = "CHASERS", requires = "support_action",
          value_parser = clap::value_parser!(u32).range(1..=3))]
    support_roles: Option<u32>,
    /// With --support-roles: the robots that do not chase may not `stay`
    /// either, so they always walk to or hold their support spot (where a
    /// pass can reach them) unless the ball is in their reach.
    #[arg(long, hide = true, requires = "support_roles")]
    support_only: bool,
    /// PPO or DQN team preset, with --support-action: where the support spot
    /// is. `ahead` (the default): 1.5 m ahead of the ball toward the opponent
    /// goal and 1 m to the side the robot is on. `facing`: 1.5 m beyond the
    /// ball on the line from the teammate nearest the ball through the ball,
    /// and 1 m to the side of that line the robot is on, which is where that
    /// teammate faces when it reaches the ball, whichever way it comes from.
    /// Recorded in the run's configuration. The reward's `support` shaping
    /// keeps its own spot (ahead); set it to 0 in the config when the spots
    /// differ.
    #[arg(long, hide = true, value_name = "SPOT", value_parser = ["ahead", "facing"],
          requires = "support_action")]
    support_spot: Option<String>,
    /// PPO or DQN team preset, with --support-action: give the robots an eighth
    /// action, `approach`, a walk round behind the ball onto the line from it
    /// to the opponent goal and then into the ball, so the robot reaches it
    /// facing that goal (as the scripted team lines up). The team's policy
    /// turns it into `forward` and turns each tick. With --support-roles only
    /// the chasers may `approach`. Recorded in the run's configuration.
    #[arg(long, hide = true, requires = "support_action")]
    approach_action: bool,
    /// With --approach-action: no robot may walk `forward` or turn; they
    /// move by `approach` and `support` only (and `stay`, `shoot`, `pass`).
    #[arg(long, hide = true, requires = "approach_action")]
    approach_only: bool,
    /// PPO or DQN team preset, with --support-action: give the robots a ninth
    /// action, `defend`, a walk back onto the line from the ball to the centre
    /// of the own goal, 1 m from the ball (at least 0.3 m out from the goal),
    /// facing the ball there: the step a team needs to stand between the ball
    /// and its goal. Every robot may choose it, chaser or not; it holds like
    /// `support` under --support-hold. Without --approach-action the network
    /// still has `approach`'s output, always masked. Recorded in the run's
    /// configuration.
    #[arg(long, hide = true, requires = "support_action")]
    defend_action: bool,
    /// PPO or DQN team preset, with --pass-action, --approach-action and
    /// --defend-action: give the robots a tenth action, `give`, a pass lined
    /// up: the robot walks round behind the ball onto the line from a free
    /// teammate 1.2-3.5 m from the ball through the ball (as `approach` lines
    /// up on the goal; teammates ahead of the ball first, then the one
    /// needing the least walk round the ball) and into the ball, and sends
    /// the protocol's `pass` once the ball is in kick reach and the pass
    /// rule names a receiver. Possible while there is such a teammate; with
    /// --support-roles only for the chasers; held under --support-hold until
    /// the ball is more than 1 m away (its pass made). Recorded in the run's
    /// configuration. A team with nine actions starting from --init-from
    /// gains `give` as a copy of `approach`, its bias --support-init-bias
    /// lower.
    #[arg(long, hide = true, requires_all = ["pass_action", "approach_action", "defend_action"])]
    give_action: bool,
    /// Team presets: the own-goal guard. Near its own goal line (the ball
    /// within 0.6 m of it, in front of the goal) a robot facing its own
    /// goal with the ball just ahead may not walk `forward` or `shoot`, so
    /// it cannot push or kick the ball into its own goal; it turns, waits
    /// or passes instead. Recorded in the run's configuration, so the team
    /// plays the same way in `match`, `eval` and over the socket.
    #[arg(long, hide = true)]
    own_goal_guard: bool,
    /// PPO team preset: start from these weights (a run directory's
    /// final.safetensors, or a .safetensors checkpoint) with a fresh
    /// optimiser; the networks must have the run's shape, except that a
    /// team trained without `pass`, `support` or `approach` gains them
    /// (with --pass-action, --support-action and --approach-action): `pass`
    /// starts as a copy of `shoot`, `support` as `forward` made about 2.7
    /// times less likely (see --pass-init and --support-init-bias),
    /// `approach` as an exact copy of `forward`.
    #[arg(long, value_name = "DIR|FILE", conflicts_with = "resume")]
    init_from: Option<PathBuf>,
    /// With --init-from and --pass-action, from a team trained without
    /// `pass`: start `pass` as a copy of this action instead of `shoot`
    /// (forward, turn_left, turn_right, shoot or stay). `turn_left` gives a
    /// kicker that tries `pass` where it used to turn with the ball.
    #[arg(long, hide = true, value_name = "ACTION", requires_all = ["init_from", "pass_action"])]
    pass_init: Option<naosoccer_proto::Action>,
    /// With --init-from and --support-action, from a team trained without
    /// `support`: start `support`'s bias this many logits below
    /// `forward`'s (its weights are a copy of `forward`'s). 1 (the
    /// default) makes it about 2.7 times less likely than `forward`; 0
    /// starts it as likely.
    #[arg(long, hide = true, value_name = "LOGITS", requires_all = ["init_from", "support_action"], allow_negative_numbers = true)]
    support_init_bias: Option<f32>,
    /// PPO: the critic reads the whole team's observations (MAPPO).
    #[arg(long, hide = true)]
    central_critic: bool,
    /// PPO: minibatches per pass.
    #[arg(long, hide = true)]
    minibatches: Option<usize>,
    /// PPO: entropy-bonus weight at the start of the run.
    #[arg(long, hide = true)]
    entropy_coef: Option<f64>,
    /// PPO: entropy-bonus weight at the end of the run, reached linearly
    /// from --entropy-coef (the team preset: 0.002; the others: none, a
    /// constant weight).
    #[arg(long, hide = true)]
    entropy_coef_end: Option<f64>,
    /// Per-tick discount (PPO and DQN; DQN's transitions are discounted by
    /// gamma^ticks).
    #[arg(long, hide = true)]
    gamma: Option<f64>,
    /// PPO team preset: the KL early stop's target (0: no early stop).
    #[arg(long, hide = true)]
    target_kl: Option<f64>,
    /// PPO: the learning rate of actor and critic at the start; DQN: its
    /// learning rate.
    #[arg(long, hide = true)]
    lr: Option<f64>,
    /// Drill episodes instead of matches: the learners alone before the
    /// opponent goal, the ball at a random spot; an episode ends with a goal
    /// or the clock (use a short --minutes). `anywhere`: the robot anywhere
    /// within 0.8 m of the ball, facing anywhere; `behind`: within 45
    /// degrees of straight behind it, facing it +-30 degrees.
    #[arg(long, hide = true, value_parser = ["anywhere", "behind"])]
    drill: Option<String>,
    /// PPO team preset: scenario files (docs/SCENARIOS.md) the last
    /// --scenario-matches of the --matches play instead of whole matches,
    /// one episode after another, each from a scenario drawn from its seed,
    /// against the run's opponents; an episode ends with its play and every
    /// scenario match is cut at a match's length; a cut end is bootstrapped
    /// (docs/SCENARIOS.md, "Training on drills"). Repeat the option or
    /// separate files with commas; e.g. assets/scenarios/training/pass-*.toml,
    /// the pass drills.
    #[arg(
        long,
        hide = true,
        value_name = "FILE",
        value_delimiter = ',',
        requires = "scenario_matches"
    )]
    scenarios: Vec<PathBuf>,
    /// How many of the --matches play --scenarios (the last ones).
    #[arg(long, hide = true, value_name = "N", requires = "scenarios")]
    scenario_matches: Option<usize>,
    /// Observation layout version: 2 (the default), 3 (version 2 plus the
    /// pass picture: teammates seen from the robot, whether they face the
    /// ball, how clear the lane to them is), 4 (version 3 plus the shot
    /// picture: how clear the lanes from the ball along the heading and to
    /// the goal are, where the heading meets the goal line) or 1 (the
    /// shipped paper-era teams' layout; PPO only). docs/LEARNING.md lists
    /// each layout.
    #[arg(long, hide = true)]
    obs_version: Option<u32>,
    /// Opponent: scripted, a scripted variant (scripted:KEY=VAL,... or
    /// scripted:FILE.toml), random, idle, a frozen team (ppo:DIR, dqn:DIR),
    /// curriculum or schedule:STAGES (PPO; see docs/LEARNING.md) or
    /// self-play[:N] (the learner's own snapshot, refreshed every N transitions).
    #[arg(long, default_value = "scripted")]
    opponent: String,
    /// Matches played side by side.
    #[arg(long, default_value_t = 16)]
    matches: usize,
    /// Threads stepping matches [default: 2]. With --recipe or --resume:
    /// this sitting's, for every stage (also a recipe's own `threads`); the
    /// thread count changes nothing simulated or learned, only the speed.
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    threads: Option<usize>,
    /// libtorch's intra-op threads.
    #[arg(long, hide = true, default_value_t = 1)]
    torch_threads: i32,
    /// Match configuration (TOML); default: the built-in assets/match.toml.
    #[arg(long)]
    config: Option<PathBuf>,
    /// Episode (match) length in minutes, overriding the configuration.
    #[arg(long)]
    minutes: Option<f32>,
    /// Players the network controls, e.g. 0,1,2,3 (default) or 1.
    #[arg(long, hide = true, default_value = "0,1,2,3")]
    learners: String,
    /// Built-in policy of own players that do not learn.
    #[arg(long, hide = true, default_value = "idle")]
    teammates: String,
    /// Transitions between checkpoints.
    #[arg(long, default_value_t = 250_000)]
    checkpoint_every: u64,
    /// PPO: control ticks each match plays between updates.
    #[arg(long, hide = true)]
    rollout: Option<usize>,
    /// PPO: passes over each rollout.
    #[arg(long, hide = true)]
    epochs: Option<usize>,
    /// DQN: one network shared by the team instead of one per robot (the
    /// paper; the team preset always shares).
    #[arg(long, hide = true)]
    shared: bool,
    /// DQN: transitions summed into one return before bootstrapping (the
    /// paper: 1; the team preset: 3).
    #[arg(long, hide = true)]
    n_step: Option<usize>,
    /// DQN: exploration rate (the paper: 0.3, fixed; the team preset: the
    /// rate its schedule ends at).
    #[arg(long, hide = true)]
    epsilon: Option<f64>,
    /// DQN: keep a Polyak average of the learning network's weights, each
    /// gradient step `avg = K avg + (1 - K) net` (K in [0, 1), e.g. 0.9999),
    /// and save that average as the team (checkpoints, final.safetensors);
    /// the learning network's last weights go to final-online.safetensors.
    /// The average does not change what the run learns. Default: none.
    #[arg(long, hide = true, value_name = "K")]
    average: Option<f64>,
}

pub fn train_cmd(a: TrainArgs) -> anyhow::Result<()> {
    if let Some(recipe) = &a.recipe {
        let out = a.out.as_ref().context("--recipe needs --out DIR")?;
        return super::recipe::start(recipe, out, a.seed, a.threads);
    }
    if let Some(dir) = a
        .resume
        .as_ref()
        .filter(|d| super::recipe::is_recipe_run(d))
    {
        anyhow::ensure!(
            a.steps.is_none(),
            "{} is a recipe run: its stages' lengths are in its recipe.toml, not --steps",
            dir.display()
        );
        return super::recipe::run(dir, a.threads);
    }
    run_train(a, None, &mut || {})
}

/// One `train` run; `tick` is called with every progress report (a recipe
/// keeps its time file with it); `stage` names the recipe stage in the
/// progress bar.
pub(crate) fn run_train(
    a: TrainArgs,
    stage: Option<&str>,
    tick: &mut dyn FnMut(),
) -> anyhow::Result<()> {
    tch::set_num_threads(a.torch_threads.max(1));
    let mcfg = match_config(a.config.as_ref(), a.minutes)?;
    let algo = a.algo.unwrap_or(Algo::Ppo);
    let mut cfg = TrainConfig::new(algo, mcfg);
    cfg.steps = a.steps.unwrap_or(1_000_000);
    cfg.seed = a.seed;
    cfg.matches = a.matches;
    if let Some(t) = a.threads {
        cfg.threads = t;
    }
    cfg.learners = parse_players(&a.learners).map_err(anyhow::Error::msg)?;
    cfg.teammates = a
        .teammates
        .parse::<naosoccer_policy::PolicyKind>()
        .map_err(anyhow::Error::msg)?
        .to_string();
    cfg.opponent = a
        .opponent
        .parse::<OpponentSpec>()
        .map_err(anyhow::Error::msg)?;
    cfg.checkpoint_every = a.checkpoint_every;
    match algo {
        Algo::Ppo => {
            cfg.ppo = PpoConfig::preset(a.preset.parse::<Preset>().map_err(anyhow::Error::msg)?)
        }
        Algo::Dqn => {
            cfg.dqn = DqnConfig::preset(a.preset.parse::<DqnPreset>().map_err(anyhow::Error::msg)?)
        }
    }
    if let Some(r) = a.rollout {
        cfg.ppo.rollout = r;
    }
    if let Some(e) = a.epochs {
        cfg.ppo.epochs = e;
    }
    if a.shared {
        cfg.dqn.shared = true;
    }
    if let Some(n) = a.n_step {
        anyhow::ensure!(n >= 1, "--n-step must be at least 1");
        cfg.dqn.n_step = n;
    }
    if let Some(m) = a.minibatches {
        cfg.ppo.minibatches = m;
    }
    if let Some(e) = a.entropy_coef {
        cfg.ppo.entropy_coef = e;
    }
    if let Some(e) = a.entropy_coef_end {
        anyhow::ensure!(
            e >= 0.0 && e.is_finite(),
            "--entropy-coef-end must be a weight of 0 or more, not {e}"
        );
        cfg.ppo.entropy_coef_end = Some(e);
    }
    if let Some(g) = a.gamma {
        anyhow::ensure!(g > 0.0 && g <= 1.0, "--gamma must be in (0, 1], not {g}");
        match algo {
            Algo::Ppo => cfg.ppo.gamma = g,
            Algo::Dqn => cfg.dqn.gamma = g,
        }
    }
    if let Some(k) = a.target_kl {
        cfg.ppo.target_kl = (k > 0.0).then_some(k);
    }
    if let Some(lr) = a.lr {
        match algo {
            Algo::Ppo => {
                cfg.ppo.lr_actor = lr;
                cfg.ppo.lr_critic = lr;
            }
            Algo::Dqn => cfg.dqn.lr = lr,
        }
    }
    cfg.ppo.central_critic |= a.central_critic;
    let decision = match cfg.algo {
        Algo::Ppo => cfg.ppo.decision.as_mut(),
        Algo::Dqn => cfg.dqn.decision.as_mut(),
    };
    if let Some(d) = decision {
        if let Some(k) = a.persist {
            anyhow::ensure!(k >= 1, "--persist must be at least 1 tick");
            d.persist = k;
        }
        d.mask_shoot &= !a.no_shoot_mask;
        d.pass = a.pass_action;
        d.support = a.support_action;
        if let Some(k) = a.support_hold {
            d.support_hold = k;
        }
        if let Some(n) = a.support_roles {
            d.chasers = n;
        }
        d.support_only = a.support_only;
        if let Some(spot) = a.support_spot.as_deref() {
            d.support_spot = match spot {
                "facing" => naosoccer_policy::SupportSpot::Facing,
                _ => naosoccer_policy::SupportSpot::Ahead,
            };
        }
        d.approach = a.approach_action;
        d.approach_only = a.approach_only;
        d.defend = a.defend_action;
        d.give = a.give_action;
        let sim = &cfg.match_config.sim;
        d.own_goal_guard = a
            .own_goal_guard
            .then(|| naosoccer_policy::OwnGoalGuard::for_pitch(sim.field_length, sim.goal_width));
    } else {
        anyhow::ensure!(
            a.persist.is_none()
                && !a.no_shoot_mask
                && !a.pass_action
                && !a.support_action
                && !a.own_goal_guard,
            "--persist, --no-shoot-mask, --pass-action, --support-action and --own-goal-guard \
             apply to the team preset"
        );
    }
    cfg.init_from = a.init_from.clone();
    cfg.init_pass_from = a.pass_init;
    cfg.init_support_bias = a.support_init_bias;
    if let Some(v) = a.obs_version {
        cfg.obs_version = v;
    }
    cfg.drill = match a.drill.as_deref() {
        Some("behind") => Some(naosoccer_learn::env::Drill::behind_the_ball()),
        Some(_) => Some(naosoccer_learn::env::Drill::default()),
        None => None,
    };
    if let Some(n) = a.scenario_matches {
        let scenarios = a
            .scenarios
            .iter()
            .map(|p| naosoccer_learn::env::ScenarioText::read(p))
            .collect::<Result<Vec<_>, _>>()?;
        cfg.scenarios = Some(naosoccer_learn::env::ScenarioDrills {
            matches: n,
            scenarios,
        });
    }
    if let Some(k) = a.average {
        anyhow::ensure!(algo == Algo::Dqn, "--average is a DQN option (--algo dqn)");
        anyhow::ensure!(
            (0.0..1.0).contains(&k),
            "--average must be in [0, 1) (0: none), not {k}"
        );
        cfg.dqn.average = k;
    }
    if let Some(e) = a.epsilon {
        cfg.dqn.epsilon = e;
        if cfg.dqn.epsilon_decay == 0 {
            cfg.dqn.epsilon_start = e;
        }
    }
    let start = Instant::now();
    // On a terminal, a progress bar (indicatif); in a log, a line every few
    // seconds.
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(cfg.steps),
        indicatif::ProgressDrawTarget::stderr_with_hz(4),
    );
    let tty = !bar.is_hidden();
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{elapsed_precise}] [{bar:24}] {percent:>3}% {human_pos}/{human_len} transitions, {msg}",
        )
        .expect("a valid progress template")
        .progress_chars("#> "),
    );
    bar.set_prefix(
        stage
            .unwrap_or(match algo {
                Algo::Ppo => "train ppo",
                Algo::Dqn => "train dqn",
            })
            .to_string(),
    );
    let mut last_print = 0.0f64;
    // Matches end together, so most rows have no finished episode: show the
    // latest episodes that did finish.
    let mut last_episodes = "no episode finished yet".to_string();
    // The rate counts this process's transitions only: a resumed run starts
    // from its checkpoint's count (taken from its first report).
    let mut first_seen: Option<u64> = a.resume.is_none().then_some(0);
    let mut show = |p: &naosoccer_learn::metrics::Progress<'_>| {
        tick();
        let since = p.row.transitions - *first_seen.get_or_insert(p.row.transitions);
        if !p.row.episode_return.is_nan() {
            last_episodes = format!(
                "last episodes: return {:.2}, goals {:.2}:{:.2} ({} so far)",
                p.row.episode_return, p.row.goals_for, p.row.goals_against, p.row.episodes
            );
        }
        let secs = start.elapsed().as_secs_f64();
        let msg = format!(
            "{:.0}/s, reward/tick {:.4}, {}",
            since as f64 / secs.max(1e-9),
            p.row.reward,
            last_episodes,
        );
        if tty {
            bar.set_length(p.total_steps);
            bar.set_position(p.row.transitions.min(p.total_steps));
            bar.set_message(msg);
            return;
        }
        if secs - last_print < 5.0 && p.row.transitions < p.total_steps {
            return;
        }
        last_print = secs;
        let frac = p.row.transitions as f64 / p.total_steps as f64;
        eprintln!(
            "{} {:>5.1}% {} transitions, {msg}",
            bar.prefix(),
            100.0 * frac.min(1.0),
            p.row.transitions,
        );
    };
    let summary = match (&a.resume, &a.out) {
        (Some(dir), _) => naosoccer_learn::train::resume(dir, a.steps, a.threads, &mut show)?,
        (None, Some(out)) => train(&cfg, out, &mut show)?,
        (None, None) => anyhow::bail!("--out DIR is needed (or --resume DIR)"),
    };
    bar.finish();
    if tty {
        eprintln!();
    }
    let secs = start.elapsed().as_secs_f64();
    // A resumed run: the rate of this sitting's transitions.
    let here = summary.transitions - first_seen.unwrap_or(summary.transitions);
    println!(
        "trained {} for {} transitions in {:.1} s ({:.0} transitions/s); weights: {}",
        algo,
        summary.transitions,
        secs,
        here as f64 / secs,
        summary.final_weights.display()
    );
    Ok(())
}

#[derive(Args, Debug)]
#[command(after_help = "Example:
  naosoccer plot runs/ppo-1 runs/dqn-1 --out docs/learning/curves.png

Left: the team's long-term average reward (running mean since the start of
training) against timeslots (control ticks per match); right: the same per
robot. One colour per run.")]
pub struct PlotArgs {
    /// Run directories (or their metrics.csv files).
    #[arg(required = true)]
    runs: Vec<PathBuf>,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
}

pub fn plot_cmd(a: PlotArgs) -> anyhow::Result<()> {
    naosoccer_learn::plot::plot_runs(&a.runs, &a.out)?;
    println!("wrote {}", a.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 41, item 3: `train --help` shows at most 15 options (help
    /// included), counts the others rightly, and every option, shown or
    /// not, is in the guide's table of recipe fields.
    #[test]
    fn train_help_is_short_and_the_guide_lists_every_option() {
        let cmd = TrainArgs::augment_args(clap::Command::new("train"));
        let shown: Vec<String> = cmd
            .get_arguments()
            .filter(|a| !a.is_hide_set())
            .filter_map(|a| a.get_long().map(str::to_string))
            .collect();
        assert!(
            shown.len() < 15,
            "{} options besides --help: {shown:?}",
            shown.len()
        );
        let guide = include_str!("../../docs/LEARNING.md");
        let table = guide
            .split("### Recipe fields: every option of `train`")
            .nth(1)
            .and_then(|s| s.split("\n## ").next())
            .expect("LEARNING.md has the recipe fields section");
        for long in shown.iter() {
            assert!(
                table.contains(&format!("`--{long}`")),
                "--{long} is named among the options of every day"
            );
        }
        // The help's count of the options it does not show.
        let hidden = cmd.get_arguments().filter(|a| a.is_hide_set()).count();
        let after = cmd
            .get_after_help()
            .map(|h| h.to_string())
            .unwrap_or_default();
        assert!(
            after.contains(&format!("teammates: {hidden} in all)")),
            "train --help counts {hidden} options besides those it shows"
        );
        for a in cmd.get_arguments() {
            let long = a.get_long().unwrap();
            let named = table.match_indices(&format!("--{long}")).any(|(i, m)| {
                !table[i + m.len()..].starts_with(|c: char| c.is_ascii_alphanumeric() || c == '-')
            });
            assert!(
                named,
                "--{long} is missing from LEARNING.md's recipe fields"
            );
        }
    }
}
