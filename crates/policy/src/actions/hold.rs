//! The decision-level MDP's state of one robot: the action it holds and
//! until when.

use naosoccer_proto::{Observation, Tick};

use super::{
    defend_spot, give_target, support_spot, DecisionConfig, NetAction, SupportSpot,
    GIVE_RELEASE_BALL, SUPPORT_ARRIVE, SUPPORT_RELEASE_BALL,
};

/// One robot's decision state in the decision-level MDP (`team` preset):
/// the action it holds and until which tick. The trainer and
/// [`crate::LearnedPolicy`] both use it, so a team decides in play exactly
/// when it decided in training, in process or over the socket.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Hold {
    action: NetAction,
    until: Tick,
    last_tick: Option<Tick>,
    /// A `support` or `defend` held to its spot, or a `give` held to its
    /// kick ([`DecisionConfig::support_hold`]): from this tick on it also
    /// ends on arrival or with the ball near (`give`: with no teammate to
    /// give to, or the ball away).
    release_from: Option<Tick>,
    /// The pitch's half length and half width (m), and where the spot is.
    half: [f32; 2],
    spot: SupportSpot,
}

impl Hold {
    /// Whether the robot that received `obs` decides now: it is free to act
    /// (not lying, not busy in a kick) and its last decision's persistence
    /// has run out (for a `support` or `defend` held to its spot: also once
    /// it arrived or the ball came near; for a held `give`: also once there
    /// is no teammate to give to or the ball is more than
    /// [`GIVE_RELEASE_BALL`] away, as after its kick). A tick earlier than
    /// the last one seen is a new match.
    pub fn must_decide(&mut self, obs: &Observation) -> bool {
        if self.last_tick.is_some_and(|t| obs.tick < t) {
            *self = Hold::default();
        }
        self.last_tick = Some(obs.tick);
        if !is_free(obs) {
            return false;
        }
        if obs.tick >= self.until {
            return true;
        }
        match self.release_from {
            Some(from) if obs.tick >= from && self.action == NetAction::Give => {
                let me = obs.me();
                let ball = (obs.ball.x - me.x).hypot(obs.ball.y - me.y);
                ball > GIVE_RELEASE_BALL || give_target(obs).is_none()
            }
            Some(from) if obs.tick >= from => {
                let me = obs.me();
                let spot = if self.action == NetAction::Defend {
                    defend_spot(obs, self.half)
                } else {
                    support_spot(obs, self.half, self.spot)
                };
                let arrived = (spot[0] - me.x).hypot(spot[1] - me.y) <= SUPPORT_ARRIVE;
                let ball_near =
                    (obs.ball.x - me.x).hypot(obs.ball.y - me.y) <= SUPPORT_RELEASE_BALL;
                arrived || ball_near
            }
            _ => false,
        }
    }

    /// The action of a robot that does not decide now: what it holds while
    /// free, `stay` while lying or kicking (its action is ignored then).
    pub fn held(&self, obs: &Observation) -> NetAction {
        if is_free(obs) {
            self.action
        } else {
            NetAction::Stay
        }
    }

    /// Records a decision at `tick` under `decision`, on a pitch of half
    /// length and half width `half` (m): a movement lasts `persist` ticks, a
    /// `shoot` or `pass` one (the kick then keeps the robot busy), a
    /// `support` or `defend` with `support_hold` until its robot arrives,
    /// the ball comes near or `support_hold` ticks pass, a `give` with
    /// `support_hold` until there is no one to give to, the ball is away
    /// (its pass made) or `support_hold` ticks pass.
    pub fn start(
        &mut self,
        action: NetAction,
        tick: Tick,
        decision: &DecisionConfig,
        half: [f32; 2],
    ) {
        self.action = action;
        let persist = u64::from(decision.persist.max(1));
        self.release_from = None;
        let ticks = if action.is_kick() {
            1
        } else if matches!(
            action,
            NetAction::Support | NetAction::Defend | NetAction::Give
        ) && u64::from(decision.support_hold) > persist
        {
            self.release_from = Some(tick + persist);
            self.half = half;
            self.spot = decision.support_spot;
            u64::from(decision.support_hold)
        } else {
            persist
        };
        self.until = tick + ticks;
    }

    /// Forgets the hold (the episode ended).
    pub fn reset(&mut self) {
        *self = Hold::default();
    }
}

/// Not lying and not in a kick.
pub fn is_free(obs: &Observation) -> bool {
    let me = obs.me();
    !me.fallen && !me.busy
}
