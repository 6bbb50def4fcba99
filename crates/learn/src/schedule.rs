//! Opponent schedules: a curriculum of stages, each a weighted mix of
//! opponents, and a pool of the learner's past snapshots to mix in.
//!
//! A stage lasts until a number of transitions (the last one to the end of
//! the run). Its mix names opponents by spec: `idle`, `random`, `scripted`,
//! a frozen team (`ppo:DIR`, `dqn:DIR`), `self` (the learner's latest
//! snapshot) or `pool` (one of the last `pool_size` snapshots, equally
//! likely). Every match draws its opponent for each episode from the mix
//! (a hash of the run's seed, the match and the episode), and the learner
//! still plays blue in even-numbered matches and red in odd ones.
//!
//! On the command line: `--opponent curriculum` (the default schedule,
//! [`Schedule::curriculum`]) or `--opponent schedule:STAGE,STAGE,...` with
//! `STAGE = SPEC[=WEIGHT][+SPEC[=WEIGHT]...][@UNTIL]`, e.g.
//! `schedule:idle@1000000,random@2000000,scripted=1+pool=1`.
//!
//! This module is what a schedule says (it is part of the run's
//! configuration); [`crate::schedule_runner`] plays one.

use naosoccer_policy::PolicyKind;
use serde::{Deserialize, Serialize};

/// One stage of a schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    /// The stage lasts while the run has made fewer transitions than this;
    /// `None` (the last stage): to the end.
    pub until: Option<u64>,
    /// Opponent specs and their weights.
    pub mix: Vec<(String, f64)>,
}

/// A curriculum of opponent mixes and the snapshot pool's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    pub stages: Vec<Stage>,
    /// Transitions between two snapshots of the learner.
    pub pool_every: u64,
    /// Snapshots kept (the most recent).
    pub pool_size: usize,
}

impl Schedule {
    /// The default: idle opponents for 1M transitions (learn to reach the
    /// ball and score), random ones until 3M, the scripted team until 8M,
    /// then the scripted team half of the time and a past snapshot the other
    /// half; a snapshot every 1M transitions, the last 8 kept.
    pub fn curriculum() -> Schedule {
        Schedule {
            stages: vec![
                Stage {
                    until: Some(1_000_000),
                    mix: vec![("idle".into(), 1.0)],
                },
                Stage {
                    until: Some(3_000_000),
                    mix: vec![("random".into(), 1.0)],
                },
                Stage {
                    until: Some(8_000_000),
                    mix: vec![("scripted".into(), 1.0)],
                },
                Stage {
                    until: None,
                    mix: vec![("scripted".into(), 1.0), ("pool".into(), 1.0)],
                },
            ],
            pool_every: 1_000_000,
            pool_size: 8,
        }
    }

    /// Parses the `schedule:` form (without the prefix); see the module docs.
    pub fn parse(s: &str) -> Result<Schedule, String> {
        let mut stages = Vec::new();
        for stage in s.split(',') {
            let (mix, until) = match stage.split_once('@') {
                Some((m, u)) => (
                    m,
                    Some(
                        u.parse::<u64>()
                            .map_err(|_| format!("bad stage end {u:?} in {stage:?}"))?,
                    ),
                ),
                None => (stage, None),
            };
            let mut entries = Vec::new();
            for e in mix.split('+') {
                let (spec, w) = match e.rsplit_once('=') {
                    Some((spec, w)) => (
                        spec,
                        w.parse::<f64>()
                            .map_err(|_| format!("bad weight {w:?} in {stage:?}"))?,
                    ),
                    None => (e, 1.0),
                };
                check_spec(spec)?;
                if !(w.is_finite() && w > 0.0) {
                    return Err(format!("weights must be positive, got {w} in {stage:?}"));
                }
                entries.push((spec.to_string(), w));
            }
            stages.push(Stage {
                until,
                mix: entries,
            });
        }
        let sched = Schedule {
            stages,
            ..Schedule::curriculum()
        };
        sched.validate()?;
        Ok(sched)
    }

    pub(crate) fn validate(&self) -> Result<(), String> {
        if self.stages.is_empty() {
            return Err("a schedule needs at least one stage".into());
        }
        let mut last = 0;
        for (i, st) in self.stages.iter().enumerate() {
            match st.until {
                Some(u) if u <= last && i > 0 => {
                    return Err("stage ends must increase".into());
                }
                Some(u) => last = u,
                None if i + 1 < self.stages.len() => {
                    return Err("only the last stage may run to the end".into());
                }
                None => {}
            }
            if st.mix.is_empty() {
                return Err(format!("stage {i} has no opponent"));
            }
        }
        if self.pool_size == 0 || self.pool_every == 0 {
            return Err("pool_size and pool_every must be positive".into());
        }
        Ok(())
    }

    /// The stage in force after `transitions`.
    pub fn stage_at(&self, transitions: u64) -> usize {
        self.stages
            .iter()
            .position(|s| s.until.is_none_or(|u| transitions < u))
            .unwrap_or(self.stages.len() - 1)
    }

    pub(crate) fn uses_snapshots(&self, stage: usize) -> bool {
        self.stages[stage]
            .mix
            .iter()
            .any(|(s, _)| s == "pool" || s == "self")
    }
}

fn check_spec(spec: &str) -> Result<(), String> {
    if matches!(spec, "pool" | "self") || spec.starts_with("ppo:") || spec.starts_with("dqn:") {
        return Ok(());
    }
    spec.parse::<PolicyKind>()
        .map(|_| ())
        .map_err(|e| format!("{e}; or ppo:DIR, dqn:DIR, self, pool"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedules_parse_and_find_their_stage() {
        let s = Schedule::parse("idle@100,random=2+scripted@300,scripted+pool=3").unwrap();
        assert_eq!(s.stages.len(), 3);
        assert_eq!(
            s.stages[1].mix,
            vec![("random".to_string(), 2.0), ("scripted".to_string(), 1.0)]
        );
        assert_eq!(s.stages[2].until, None);
        assert_eq!(
            [
                s.stage_at(0),
                s.stage_at(99),
                s.stage_at(100),
                s.stage_at(299),
                s.stage_at(300)
            ],
            [0, 0, 1, 1, 2]
        );
        assert!(s.uses_snapshots(2) && !s.uses_snapshots(1));
        assert!(Schedule::parse("idle@100,random@50,scripted").is_err());
        assert!(
            Schedule::parse("idle,random").is_err(),
            "an open stage must be last"
        );
        assert!(Schedule::parse("goalie@5,scripted").is_err());
        assert!(Schedule::parse("idle=0").is_err());
        Schedule::curriculum().validate().unwrap();
    }
}
