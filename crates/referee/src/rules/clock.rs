//! The match clock and its halves. Game time is a count of control ticks;
//! wall-clock time never enters. With two halves the first is the first
//! `total / 2` ticks; when its last tick has been played the referee calls
//! half time and the second half starts with a kick-off by the team that did
//! not kick off the first.

use naosoccer_proto::{Event, Team, Tick};

use super::outcome::{Command, Outcome};

#[derive(Debug, Clone, Copy)]
pub struct Clock {
    total_ticks: u64,
    control_hz: f32,
    /// The first tick of the second half (`total_ticks` with one half).
    second_half: Tick,
}

impl Clock {
    pub fn new(minutes: f32, control_hz: f32, halves: u32) -> Clock {
        let total_ticks = (f64::from(minutes) * 60.0 * f64::from(control_hz))
            .round()
            .max(1.0) as u64;
        let second_half = Tick::new(if halves >= 2 && total_ticks >= 2 {
            total_ticks / 2
        } else {
            total_ticks
        });
        Clock {
            total_ticks,
            control_hz,
            second_half,
        }
    }

    pub fn total_ticks(&self) -> u64 {
        self.total_ticks
    }

    /// The first tick of half `half` (1 or 2) and the tick after its last
    /// (`None` for a half the match does not have).
    pub fn half_span(&self, half: u8) -> Option<(Tick, Tick)> {
        match half {
            1 => Some((Tick::ZERO, self.second_half)),
            2 if self.second_half.get() < self.total_ticks => {
                Some((self.second_half, Tick::new(self.total_ticks)))
            }
            _ => None,
        }
    }

    /// The half that the tick `tick` is in: 1 or 2.
    pub fn half(&self, tick: Tick) -> u8 {
        if tick >= self.second_half {
            2
        } else {
            1
        }
    }

    /// At the last tick of the first half: `HalfTime` and the second half's
    /// kick-off by `second_kicker`. Returns whether it was half time.
    pub fn check_half_time(&self, tick: Tick, second_kicker: Team, out: &mut Outcome) -> bool {
        let half_time =
            self.second_half.get() < self.total_ticks && tick.next() == self.second_half;
        if half_time {
            out.events.push(Event::HalfTime { tick });
            out.commands.push(Command::KickOff {
                team: second_kicker,
            });
        }
        half_time
    }

    /// Seconds of game time left when `tick` ticks have been played.
    pub fn time_left(&self, tick: Tick) -> f32 {
        self.total_ticks.saturating_sub(tick.get()) as f32 / self.control_hz
    }

    /// Emits `End` when the tick being played is the last one.
    pub fn check(&self, tick: Tick, out: &mut Outcome) -> bool {
        let last = tick.next().get() >= self.total_ticks;
        if last {
            out.events.push(Event::End { tick });
        }
        last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_minutes_at_ten_hertz_is_six_thousand_ticks() {
        let c = Clock::new(10.0, 10.0, 1);
        assert_eq!(c.total_ticks(), 6000);
        assert_eq!(c.time_left(Tick::ZERO), 600.0);
        assert_eq!(c.time_left(Tick::new(5990)), 1.0);
        let mut out = Outcome::default();
        assert!(!c.check(Tick::new(5998), &mut out));
        assert!(c.check(Tick::new(5999), &mut out));
        assert_eq!(
            out.events,
            vec![Event::End {
                tick: Tick::new(5999)
            }]
        );
    }

    #[test]
    fn two_halves_split_the_ticks_and_the_other_team_kicks_off_the_second() {
        let c = Clock::new(10.0, 10.0, 2);
        assert_eq!(
            (
                c.half(Tick::ZERO),
                c.half(Tick::new(2999)),
                c.half(Tick::new(3000)),
                c.half(Tick::new(5999))
            ),
            (1, 1, 2, 2)
        );
        let mut out = Outcome::default();
        assert!(!c.check_half_time(Tick::new(2998), Team::Red, &mut out));
        assert!(!c.check_half_time(Tick::new(3000), Team::Red, &mut out));
        assert!(out.events.is_empty());
        assert!(c.check_half_time(Tick::new(2999), Team::Red, &mut out));
        assert_eq!(
            out.events,
            vec![Event::HalfTime {
                tick: Tick::new(2999)
            }]
        );
        assert_eq!(out.commands, vec![Command::KickOff { team: Team::Red }]);
        // One half: never half time.
        let one = Clock::new(10.0, 10.0, 1);
        let mut out = Outcome::default();
        assert!((0..6000).all(|t| !one.check_half_time(Tick::new(t), Team::Red, &mut out)));
        assert_eq!(one.half(Tick::new(5999)), 1);
    }
}
