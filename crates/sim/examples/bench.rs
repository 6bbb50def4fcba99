//! Cost of simulated play: bare rapier stepping of the match's bodies (the
//! floor, `BareWorld`: robots walked, turned and stood and the ball sent off
//! by setting velocities, as much motion as a scripted match) against
//! `Sim::step` with every robot under control.
//!
//! ```text
//! cargo run --release -p naosoccer-sim --example bench -- [SECONDS] [chase|walk|stay]
//! ```
//!
//! `chase` (the default) is the worst case: all eight robots chase the one
//! ball for the whole time, a permanent scrum. `walk` keeps them walking and
//! turning apart; `stay` keeps them standing. Figures are wall-clock seconds
//! of this process, so run it on a quiet machine.

use std::time::Instant;

use naosoccer_sim::{Action, BareWorld, RobotModel, Sim, SimConfig, ROBOTS};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seconds: f32 = match args.next() {
        Some(s) => s.parse().map_err(|e| format!("SECONDS `{s}`: {e}"))?,
        None => 600.0,
    };
    let mode = args.next().unwrap_or_else(|| "chase".into());
    if !["chase", "walk", "stay"].contains(&mode.as_str()) {
        return Err(format!("unknown mode `{mode}`: chase, walk or stay").into());
    }
    let cfg = SimConfig::default();
    let model = RobotModel::builtin()?;
    let steps = cfg.steps_for(seconds);

    let mut bare = BareWorld::new(&cfg, &model)?;
    let t = Instant::now();
    for _ in 0..steps {
        bare.step();
    }
    let bare_s = t.elapsed().as_secs_f64();

    let mut sim = Sim::new(&cfg, &model, 7)?;
    let per_tick = (0.1 / cfg.dt).round().max(1.0) as u64;
    let (mut kicks, mut falls) = (0, 0);
    let t = Instant::now();
    for k in 0..steps {
        if k % per_tick == 0 {
            let tick = k / per_tick;
            match mode.as_str() {
                "chase" => chase_ball(&mut sim, tick),
                "walk" => {
                    let cmd = if tick % 40 < 20 {
                        Action::Forward
                    } else {
                        Action::TurnLeft
                    };
                    for i in 0..ROBOTS {
                        sim.set_command(i, cmd);
                    }
                }
                _ => {}
            }
        }
        sim.step();
        kicks += sim.snapshot().kicks.len();
        for i in 0..ROBOTS {
            if sim.snapshot().robots[i].fallen {
                falls += 1;
                sim.stand_up(i);
            }
        }
    }
    let sim_s = t.elapsed().as_secs_f64();
    let us = |s: f64| s * 1e6 / steps as f64;
    println!(
        "{seconds} s of play ({mode}), dt {:.4} s, {steps} steps",
        cfg.dt
    );
    println!("  bare world: {bare_s:.3} s ({:.1} us/step)", us(bare_s));
    println!(
        "  sim:        {sim_s:.3} s ({:.1} us/step), {:.2}x the bare world; {kicks} kicks, {falls} falls",
        us(sim_s),
        sim_s / bare_s
    );
    Ok(())
}

/// Every robot turns toward the ball, walks to it and kicks; ball and robots
/// are put back when they leave the field.
fn chase_ball(sim: &mut Sim, tick: u64) {
    let snap = sim.snapshot().clone();
    let b = snap.ball.pos;
    if b[0].abs() > 3.0 || b[1].abs() > 2.25 {
        sim.place_ball(0.0, 0.0);
    }
    for (i, r) in snap.robots.iter().enumerate() {
        if r.pos[0].abs() > 3.3 || r.pos[1].abs() > 2.5 {
            let (x, y, h) = sim.default_spot(i);
            sim.place_robot(i, x, y, h);
        }
        let (dx, dy) = (b[0] - r.pos[0], b[1] - r.pos[1]);
        let err = (dy.atan2(dx) - r.heading + std::f32::consts::PI)
            .rem_euclid(std::f32::consts::TAU)
            - std::f32::consts::PI;
        let cmd = if dx.hypot(dy) < 0.22 && err.abs() < 0.3 {
            Action::Shoot
        } else if err > 0.25 {
            Action::TurnLeft
        } else if err < -0.25 {
            Action::TurnRight
        } else if (tick + i as u64) % 50 == 0 {
            Action::Stay
        } else {
            Action::Forward
        };
        sim.set_command(i, cmd);
    }
}
