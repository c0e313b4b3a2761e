//! The harmonic fill of one void component: a pull–push starting estimate,
//! then multigrid W-cycles until the estimated remaining error is below the
//! tolerance (steps 2–4 of [`super`]).
//!
//! Multigrid after Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd
//! ed., SIAM 2000): W-cycles, red–black Gauss–Seidel smoothing, Galerkin
//! coarse operators.

use super::patch::{Level, COARSEST_UNKNOWNS, KNOWN, SMOOTHING_SWEEPS};

/// How a component's solve went.
#[derive(Default)]
pub(super) struct Solved {
    pub(super) iterations: usize,
    pub(super) total_sweeps: usize,
    pub(super) converged: bool,
    /// A coarsest-level solve fell back to sweeps and did not converge.
    pub(super) coarsest_failed: bool,
    pub(super) last_change_m: f64,
}

/// The harmonic fill of one component: a pull–push starting estimate, then
/// multigrid W-cycles until the estimated remaining error is below the
/// tolerance (metres) or after `max_iterations` cycles; a component too
/// small to coarsen is solved directly.
pub(super) fn harmonic(
    mut fine: Level,
    tolerance_m: f64,
    max_iterations: usize,
) -> (Level, Solved) {
    start_estimate(&mut fine);
    let mut levels = vec![fine];
    while let Some(coarse) = levels.last().and_then(Level::coarsen_error) {
        levels.push(coarse);
    }
    let mut s = Solved::default();
    if levels.len() == 1 {
        // Small enough to solve exactly.
        let (sweeps, converged) = levels[0].solve_coarsest();
        s.iterations = 1;
        s.total_sweeps = sweeps;
        s.converged = converged;
        let fine = levels.swap_remove(0);
        return (fine, s);
    }
    let mut previous = Vec::new();
    // Changes of the last three cycles, newest first.
    let mut changes = [f64::INFINITY; 3];
    while s.iterations < max_iterations && remaining_error(&changes) >= tolerance_m {
        let fine = &levels[0];
        previous.clear();
        previous.extend(fine.unknowns.iter().map(|u| fine.value[u.at]));
        let (sweeps, converged) = w_cycle(&mut levels);
        s.total_sweeps += sweeps;
        s.coarsest_failed |= !converged;
        let fine = &levels[0];
        let change = fine
            .unknowns
            .iter()
            .zip(&previous)
            .map(|(u, p)| (fine.value[u.at] - p).abs())
            .fold(0.0, f64::max);
        changes = [change, changes[0], changes[1]];
        s.iterations += 1;
    }
    s.last_change_m = if s.iterations == 0 { 0.0 } else { changes[0] };
    s.converged = !s.coarsest_failed && remaining_error(&changes) < tolerance_m;
    let fine = levels.swap_remove(0);
    (fine, s)
}

/// Estimated distance of the current iterate from the solution, from the last
/// changes (newest first) of a linearly converging iteration: change × ρ / (1 −
/// ρ), with the contraction ρ the larger of the last two ratios of successive
/// changes kept within [0.5, 0.99], doubled because early ratios underestimate
/// ρ. It is never below twice the last change. Infinite until three changes are known.
fn remaining_error(changes: &[f64; 3]) -> f64 {
    if changes[0] == 0.0 {
        return 0.0;
    }
    if !changes.iter().all(|c| c.is_finite()) {
        return f64::INFINITY;
    }
    let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 1.0 };
    let rho = ratio(changes[0], changes[1])
        .max(ratio(changes[1], changes[2]))
        .clamp(0.5, 0.99);
    2.0 * changes[0] * rho / (1.0 - rho)
}

/// One W-cycle from `levels[0]` down (each coarse level is visited twice per
/// visit of the finer one); returns the sweeps done on all levels and whether
/// every coarsest solve succeeded.
fn w_cycle(levels: &mut [Level]) -> (usize, bool) {
    let Some((fine, rest)) = levels.split_first_mut() else {
        return (0, true);
    };
    let Some(coarse) = rest.first_mut() else {
        return fine.solve_coarsest();
    };
    for _ in 0..SMOOTHING_SWEEPS {
        fine.sweep();
    }
    fine.restrict_residual(coarse);
    // Two cycles on the coarse error equation (its right-hand side stays).
    let (first, ok_first) = w_cycle(rest);
    let (second, ok_second) = w_cycle(rest);
    if let Some(coarse) = rest.first() {
        fine.interpolate_from(coarse, true);
    }
    for _ in 0..SMOOTHING_SWEEPS {
        fine.sweep();
    }
    (first + second + 2 * SMOOTHING_SWEEPS, ok_first && ok_second)
}

/// Pull–push starting values: the known values averaged down a pyramid of 2×2
/// blocks (a block with any known cell is known) until few unknowns remain,
/// which start at the mean of the known cells, then interpolated back up.
fn start_estimate(level: &mut Level) {
    if level.unknowns.len() > COARSEST_UNKNOWNS {
        let mut coarse = level.coarsen_values();
        if !coarse.unknowns.is_empty() {
            start_estimate(&mut coarse);
        }
        level.interpolate_from(&coarse, false);
    } else {
        let (mut sum, mut n) = (0.0, 0usize);
        for (s, v) in level.state.iter().zip(&level.value) {
            if *s == KNOWN {
                sum += v;
                n += 1;
            }
        }
        let mean = if n > 0 { sum / n as f64 } else { 0.0 };
        for u in &level.unknowns {
            level.value[u.at] = mean;
        }
    }
}
