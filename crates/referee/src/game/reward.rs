//! The rewards of `Match`: the paper's terms per robot and tick, the
//! shaping potentials and the per-tick charges and payments.

use super::*;

impl Match {
    /// Each robot's shaping potential in the current state: `progress`
    /// times the ball's x in its team's frame minus `approach` times its
    /// distance to the ball; with `support`, the approach term only for its
    /// team's chaser, `support` times the distance to its support spot for
    /// the `support_robots` next nearest, and neither for the rest
    /// (`RewardConfig::support`).
    pub(super) fn potentials(&self) -> [f32; ROBOTS] {
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let [bx, by, _] = snap.ball.pos;
        let dist = ball_distances(snap);
        if w.support <= 0.0 {
            return std::array::from_fn(|i| {
                let sx = if i < PLAYERS_PER_TEAM { 1.0 } else { -1.0 };
                w.progress * sx * bx - w.approach * dist[i]
            });
        }
        // Each robot's rank in its team by distance to the ball (the lower
        // index first on a tie): 0 is the team's chaser.
        let rank = |i: usize| teammates(i).filter(|&j| nearer_ball(&dist, j, i)).count();
        let (lx, ly) = (
            (self.field.half_length - 0.3).max(0.0),
            (self.field.half_width - 0.3).max(0.0),
        );
        std::array::from_fn(|i| {
            let team = i / PLAYERS_PER_TEAM;
            let sx = if team == 0 { 1.0 } else { -1.0 };
            let progress = w.progress * sx * bx;
            match rank(i) {
                0 => return progress - w.approach * dist[i],
                r if r > w.support_robots as usize => return progress,
                _ => {}
            }
            let r = &snap.robots[i];
            let side = if r.pos[1] >= by { 1.0 } else { -1.0 };
            let spot_x = (bx + sx * w.support_ahead).clamp(-lx, lx);
            let spot_y = (by + side * w.support_side).clamp(-ly, ly);
            progress - w.support * (spot_x - r.pos[0]).hypot(spot_y - r.pos[1])
        })
    }

    /// `RewardConfig::crowd`: charges each standing robot within
    /// `crowd_radius` of a standing teammate nearer the ball, in the state
    /// the tick's physics reached (before any restart).
    pub(super) fn charge_crowding(&mut self) {
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let down = self.fall.down();
        let dist = ball_distances(snap);
        for i in 0..ROBOTS {
            if down[i] {
                continue;
            }
            let [x, y, _] = snap.robots[i].pos;
            let crowded = teammates(i).any(|j| {
                let [xj, yj, _] = snap.robots[j].pos;
                !down[j] && nearer_ball(&dist, j, i) && (xj - x).hypot(yj - y) < w.crowd_radius
            });
            if crowded {
                self.shaping[i] -= w.crowd;
            }
        }
    }

    /// `RewardConfig::ahead`: pays each standing robot but its team's
    /// chaser that stands ahead of the ball, in the state the tick's
    /// physics reached (before any restart), while its team has the ball
    /// (a teammate controlled it at the start of the tick).
    pub(super) fn pay_ahead(&mut self) {
        let Some(holder) = self.controller else {
            return;
        };
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let down = self.fall.down();
        let bx = snap.ball.pos[0];
        let dist = ball_distances(snap);
        let sx = if holder.index() < PLAYERS_PER_TEAM {
            1.0
        } else {
            -1.0
        };
        for i in teammates(holder.index()) {
            let chaser = !teammates(i).any(|j| nearer_ball(&dist, j, i));
            if down[i] || chaser || dist[i] < w.ahead_min || dist[i] > w.ahead_max {
                continue;
            }
            if sx * (snap.robots[i].pos[0] - bx) < w.ahead_by {
                continue;
            }
            self.shaping[i] += w.ahead;
        }
    }

    /// Per-robot reward of the last tick for `team` (learn's MDP):
    /// `s = r_goal + r_close + r_control - r_opponent_control`, returned as
    /// `sign(s) * ln(1 + |s|)` (DESIGN.md explains why not the paper's
    /// `-log(s)`), plus the shaping terms outside the log: potential-based
    /// progress and approach, and the pass and aim bonuses (`RewardConfig`). All 0
    /// before the first tick.
    pub fn rewards(&self, team: Team) -> [f32; PLAYERS_PER_TEAM] {
        let shared = self.shared_reward(team);
        std::array::from_fn(|p| self.player_reward(team, p, shared))
    }

    /// One robot's entry of [`Match::rewards`].
    pub fn reward(&self, team: Team, player: usize) -> f32 {
        self.player_reward(team, player, self.shared_reward(team))
    }

    /// The terms every robot of `team` shares: goal, opponent control.
    pub(super) fn shared_reward(&self, team: Team) -> [f32; 2] {
        let w = &self.cfg.reward;
        let goal = match self.last_goal {
            Some(t) if t == team => w.goal,
            Some(_) => -w.goal,
            None => 0.0,
        };
        let opponent = match self.controller {
            Some(c) if c.team() != team => -w.opponent_control,
            _ => 0.0,
        };
        [goal, opponent]
    }

    pub(super) fn player_reward(&self, team: Team, player: usize, shared: [f32; 2]) -> f32 {
        let Some(robot) = RobotId::new(team, player) else {
            return 0.0;
        };
        if self.tick == Tick::ZERO {
            return 0.0;
        }
        let w = &self.cfg.reward;
        let snap = self.sim.snapshot();
        let r = &snap.robots[robot.index()];
        let d = (snap.ball.pos[0] - r.pos[0]).hypot(snap.ball.pos[1] - r.pos[1]);
        let close = w.close * (-d / w.close_scale).exp();
        let control = if self.controller == Some(robot) {
            w.control
        } else {
            0.0
        };
        let [goal, opponent] = shared;
        // The order of the sum is part of the reward's bits (and of every
        // training run's): keep it.
        log_compress(goal + close + control + opponent) + self.shaping[robot.index()]
    }
}

/// Each robot's horizontal distance to the ball.
pub(super) fn ball_distances(snap: &naosoccer_sim::Snapshot) -> [f32; ROBOTS] {
    let [bx, by, _] = snap.ball.pos;
    std::array::from_fn(|i| {
        let r = &snap.robots[i];
        (bx - r.pos[0]).hypot(by - r.pos[1])
    })
}

/// The robot indices of robot `i`'s team, `i` included.
pub(super) fn teammates(i: usize) -> std::ops::Range<usize> {
    let first = i / PLAYERS_PER_TEAM * PLAYERS_PER_TEAM;
    first..first + PLAYERS_PER_TEAM
}

/// Whether robot `j` is nearer the ball than robot `i` (the lower index on
/// a tie; never `i` itself): the order that picks a team's chaser.
pub(super) fn nearer_ball(dist: &[f32; ROBOTS], j: usize, i: usize) -> bool {
    dist[j] < dist[i] || (dist[j] == dist[i] && j < i)
}

/// The pass bonus of `RewardConfig::pass`, for a long enough forward pass.
pub(super) fn pass_bonus(w: &RewardConfig, shaping: &mut [f32; ROBOTS], p: PassMade) {
    if w.pass <= 0.0 {
        return;
    }
    let long = (p.end[0] - p.start[0]).hypot(p.end[1] - p.start[1]) >= w.pass_min_distance;
    let forward = (p.end[0] - p.start[0]) * p.from.team().direction() > 0.0;
    if long && forward {
        shaping[p.from.index()] += w.pass;
        shaping[p.to.index()] += w.pass;
    }
}

/// Whether `kicker`'s kick, just made, sends the ball at a standing
/// teammate ahead (`RewardConfig::aim`).
pub(super) fn aims_at_teammate(
    w: &RewardConfig,
    snap: &naosoccer_sim::Snapshot,
    down: &[bool; ROBOTS],
    kicker: RobotId,
) -> bool {
    let [bx, by, _] = snap.ball.pos;
    let [vx, vy, _] = snap.ball.vel;
    let speed = vx.hypot(vy);
    if speed <= 0.0 {
        return false;
    }
    let team = kicker.team();
    let cos_max = w.aim_angle.cos();
    (0..PLAYERS_PER_TEAM).any(|p| {
        let Some(mate) = RobotId::new(team, p) else {
            return false;
        };
        if mate == kicker || down[mate.index()] {
            return false;
        }
        let r = &snap.robots[mate.index()].pos;
        let (dx, dy) = (r[0] - bx, r[1] - by);
        let d = dx.hypot(dy);
        d >= w.pass_min_distance
            && d <= w.aim_range
            && dx * team.direction() > 0.0
            && (dx * vx + dy * vy) >= cos_max * d * speed
            && (w.aim_lane <= 0.0 || lane_clear(snap, team, [bx, by], [r[0], r[1]], w.aim_lane))
    })
}

/// Whether no robot of the other team stands or lies within `width` metres
/// of the segment from `from` to `to` (world frame).
pub(super) fn lane_clear(
    snap: &naosoccer_sim::Snapshot,
    team: Team,
    from: [f32; 2],
    to: [f32; 2],
    width: f32,
) -> bool {
    (0..PLAYERS_PER_TEAM)
        .filter_map(|p| RobotId::new(team.other(), p))
        .all(|o| {
            let q = &snap.robots[o.index()].pos;
            segment_distance(from, to, [q[0], q[1]]) > width
        })
}

/// `sign(s) * ln(1 + |s|)`: keeps the sign, compresses the size.
pub fn log_compress(s: f32) -> f32 {
    s.signum() * s.abs().ln_1p()
}
