//! Table I as text.

use super::TeamSummary;

/// The table as text, one row per team, for `matches` matches from global
/// index `first_match` on.
pub fn format_table(rows: &[TeamSummary], matches: usize, first_match: usize) -> String {
    let both = rows
        .iter()
        .any(|r| r.as_red.matches() > 0 && r.as_blue.matches() > 0);
    let mut s = format!(
        "{matches} matches{}{}, mean ± 95% CI; win % with its Wilson 95% interval\n\
         {:<28} {:>14} {:>18} {:>16} {:>16} {:>16} {:>16} {:>11} {:>20} {:>22} {:>15}\n",
        if first_match > 0 {
            format!(
                " (numbers {first_match} to {} of the evaluation)",
                first_match + matches - 1
            )
        } else {
            String::new()
        },
        if both {
            ", half with the sides swapped"
        } else {
            ""
        },
        "team",
        "average goals",
        "ball control %",
        "average passes",
        "aimed passes",
        "passes >= 1 m",
        "average shots",
        "W/D/L",
        "win %",
        "open-play goals for/ag",
        "restart goals"
    );
    for r in rows {
        s.push_str(&format!(
            "{:<28} {:>14} {:>18} {:>16} {:>16} {:>16} {:>16} {:>11} {:>20} {:>22} {:>15}\n",
            r.name,
            format!("{:.2}", r.goals),
            format!("{:.1}", r.control_rate),
            format!("{:.2}", r.passes),
            format!("{:.2}", r.aimed_passes),
            format!("{:.2}", r.long_passes),
            format!("{:.2}", r.shots),
            format!("{}/{}/{}", r.wins, r.draws, r.losses),
            r.win_rate.to_string(),
            format!(
                "{:.2} / {:.2}",
                r.goals_open_play.mean, r.goals_open_play_against.mean
            ),
            format!("{:.2}", r.goals_restart.mean),
        ));
    }
    if both {
        for r in rows {
            s.push_str(&format!(
                "{}: as blue {}/{}/{}, as red {}/{}/{}\n",
                r.name,
                r.as_blue.wins,
                r.as_blue.draws,
                r.as_blue.losses,
                r.as_red.wins,
                r.as_red.draws,
                r.as_red.losses
            ));
        }
    }
    s
}
