//! Game-level wire types: ids, ticks, actions, observations, events,
//! statistics.
//!
//! They live in five files, all re-exported here (and from the crate
//! root): `ids.rs` (teams, robots, players, ticks, one value per team),
//! `action.rs` (the actions, and the rule a `pass` follows), `obs.rs` (the
//! observation a player receives and its parts), `event.rs` (the
//! referee's events, goal phases, statistics) and `state.rs` (a change of
//! a match's state from outside the play: `set_state`, protocol 1.5).

mod action;
mod event;
mod ids;
mod obs;
mod state;

pub use action::*;
pub use event::*;
pub use ids::*;
pub use obs::*;
pub(crate) use state::null_as_default;
pub use state::*;

#[cfg(test)]
mod tests {
    use super::*;

    /// A tick is a plain number on the wire, as before it had a type
    /// (issue 15): the same bytes both ways, and whatever a `u64` reads.
    #[test]
    fn issue_15_a_tick_reads_and_writes_as_a_plain_number() {
        for n in [0, 1, 5999, u64::MAX] {
            let t = Tick::new(n);
            assert_eq!(serde_json::to_string(&t).unwrap(), n.to_string());
            assert_eq!(serde_json::from_str::<Tick>(&n.to_string()).unwrap(), t);
            assert_eq!(
                (t.to_string(), format!("{t:?}")),
                (n.to_string(), n.to_string())
            );
        }
        for bad in ["-1", "1.5", "\"4\"", "null", "18446744073709551616"] {
            assert!(serde_json::from_str::<Tick>(bad).is_err(), "{bad}");
        }
        let e = Event::Fall {
            tick: Tick::new(7),
            robot: RobotId::from_index(2).unwrap(),
        };
        assert_eq!(
            serde_json::to_string(&e).unwrap(),
            r#"{"kind":"fall","tick":7,"robot":2}"#
        );
    }

    #[test]
    fn ticks_add_counts_and_subtract_to_counts() {
        let t = Tick::new(10);
        assert_eq!(
            (t.next(), t + 5, t - 3),
            (Tick::new(11), Tick::new(15), Tick::new(7))
        );
        assert_eq!(Tick::new(15) - t, 5);
        assert_eq!(
            (
                t.saturating_since(Tick::new(12)),
                t.saturating_since(Tick::ZERO)
            ),
            (0, 10)
        );
        assert_eq!((Tick::ZERO.prev(), t.prev()), (None, Some(Tick::new(9))));
        let mut u = t;
        u += 2;
        assert_eq!(u64::from(u), 12);
        assert_eq!(Tick::from(12), u);
        assert!(Tick::ZERO < t && t.get() == 10);
    }
}
