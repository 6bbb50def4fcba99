//! What a run reports: the rows of `metrics.csv`, and the tally of rewards
//! and finished episodes each row sums up.

use crate::env::Episode;

/// One row of `metrics.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct MetricsRow {
    pub update: u64,
    /// Control ticks per match so far (the figures' "timeslots").
    pub timeslot: u64,
    pub transitions: u64,
    pub episodes: u64,
    /// Mean reward per robot and tick over this row's interval, for the team
    /// and per learning robot.
    pub reward: f64,
    pub reward_per_robot: Vec<f64>,
    /// Mean over episodes that ended in this interval (NaN when none did).
    pub episode_return: f64,
    pub goals_for: f64,
    pub goals_against: f64,
    /// PPO: policy loss; DQN: TD loss.
    pub loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
}

impl MetricsRow {
    pub fn header(robots: &[usize]) -> String {
        let mut h = String::from("update,timeslot,transitions,episodes,reward");
        for p in robots {
            h.push_str(&format!(",reward_p{p}"));
        }
        h.push_str(",episode_return,goals_for,goals_against,loss,value_loss,entropy");
        h
    }

    pub fn to_csv(&self) -> String {
        let mut s = format!(
            "{},{},{},{},{:.6}",
            self.update, self.timeslot, self.transitions, self.episodes, self.reward
        );
        for r in &self.reward_per_robot {
            s.push_str(&format!(",{r:.6}"));
        }
        s.push_str(&format!(
            ",{:.6},{:.4},{:.4},{:.6},{:.6},{:.6}",
            self.episode_return,
            self.goals_for,
            self.goals_against,
            self.loss,
            self.value_loss,
            self.entropy
        ));
        s
    }
}

/// What a run reports as it goes (the CLI adds wall-clock rates).
#[derive(Debug, Clone)]
pub struct Progress<'a> {
    pub row: &'a MetricsRow,
    pub total_steps: u64,
}

/// Accumulates rewards and finished episodes between metric rows.
pub(crate) struct Tally {
    robots: usize,
    reward_sum: Vec<f64>,
    samples: u64,
    pub(crate) episodes: Vec<Episode>,
    pub(crate) total_episodes: u64,
}

impl Tally {
    pub(crate) fn new(robots: usize) -> Tally {
        Tally {
            robots,
            reward_sum: vec![0.0; robots],
            samples: 0,
            episodes: Vec::new(),
            total_episodes: 0,
        }
    }

    pub(crate) fn add_rewards(&mut self, rewards: &[f32]) {
        for (i, r) in rewards.iter().enumerate() {
            self.reward_sum[i % self.robots] += f64::from(*r);
        }
        self.samples += (rewards.len() / self.robots) as u64;
    }

    pub(crate) fn row(
        &mut self,
        update: u64,
        timeslot: u64,
        transitions: u64,
        losses: (f64, f64, f64),
    ) -> MetricsRow {
        let per: Vec<f64> = self
            .reward_sum
            .iter()
            .map(|s| s / self.samples.max(1) as f64)
            .collect();
        let reward = per.iter().sum::<f64>() / per.len() as f64;
        let n = self.episodes.len();
        let mean = |f: &dyn Fn(&Episode) -> f64| {
            if n == 0 {
                f64::NAN
            } else {
                self.episodes.iter().map(f).sum::<f64>() / n as f64
            }
        };
        let episode_return = mean(&|e| {
            e.returns.iter().map(|&r| f64::from(r)).sum::<f64>() / e.returns.len() as f64
        });
        let goals_for = mean(&|e| f64::from(e.goals_for));
        let goals_against = mean(&|e| f64::from(e.goals_against));
        self.total_episodes += n as u64;
        let row = MetricsRow {
            update,
            timeslot,
            transitions,
            episodes: self.total_episodes,
            reward,
            reward_per_robot: per,
            episode_return,
            goals_for,
            goals_against,
            loss: losses.0,
            value_loss: losses.1,
            entropy: losses.2,
        };
        self.reward_sum.iter_mut().for_each(|s| *s = 0.0);
        self.samples = 0;
        self.episodes.clear();
        row
    }
}
