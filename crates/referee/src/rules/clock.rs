//! The match clock. Game time is a count of control ticks; wall-clock time
//! never enters.

use naosoccer_proto::Event;

use super::Outcome;

#[derive(Debug, Clone, Copy)]
pub struct Clock {
    total_ticks: u64,
    control_hz: f32,
}

impl Clock {
    pub fn new(minutes: f32, control_hz: f32) -> Clock {
        Clock {
            total_ticks: (f64::from(minutes) * 60.0 * f64::from(control_hz))
                .round()
                .max(1.0) as u64,
            control_hz,
        }
    }

    pub fn total_ticks(&self) -> u64 {
        self.total_ticks
    }

    /// Seconds of game time left when `tick` ticks have been played.
    pub fn time_left(&self, tick: u64) -> f32 {
        self.total_ticks.saturating_sub(tick) as f32 / self.control_hz
    }

    /// Emits `End` when the tick being played is the last one.
    pub fn check(&self, tick: u64, out: &mut Outcome) -> bool {
        let last = tick + 1 >= self.total_ticks;
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
        let c = Clock::new(10.0, 10.0);
        assert_eq!(c.total_ticks(), 6000);
        assert_eq!(c.time_left(0), 600.0);
        assert_eq!(c.time_left(5990), 1.0);
        let mut out = Outcome::default();
        assert!(!c.check(5998, &mut out));
        assert!(c.check(5999, &mut out));
        assert_eq!(out.events, vec![Event::End { tick: 5999 }]);
    }
}
