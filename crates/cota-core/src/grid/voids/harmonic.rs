//! The harmonic fill of one void component: a pull–push starting estimate,
//! then multigrid W-cycles until the estimated remaining error is below the
//! tolerance (steps 2–4 of [`super`]).
//!
//! Multigrid after Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd
//! ed., SIAM 2000): W-cycles, red–black Gauss–Seidel smoothing, Galerkin
//! coarse operators.

use super::coarse::Coarse;
use super::fine::Fine;
use super::interp::COARSEST_UNKNOWNS;
use super::pyramid::start_estimate;

/// Gauss–Seidel sweeps before and after each coarse-grid correction.
const SMOOTHING_SWEEPS: usize = 2;

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

/// The harmonic fill of one component (the unknowns of `fine`): a pull–push
/// starting estimate, then multigrid W-cycles until the estimated remaining
/// error is below the tolerance (metres), or the changes are down to the
/// `f32` rounding of the heights, or after `max_iterations` cycles; a
/// component too small to coarsen is solved directly.
pub(super) fn harmonic(fine: &mut Fine<'_>, tolerance_m: f64, max_iterations: usize) -> Solved {
    let mut s = Solved::default();
    if fine.unknowns() <= COARSEST_UNKNOWNS {
        s.iterations = 1;
        s.converged = fine.solve_direct();
        if !s.converged {
            for k in 1..=10_000 {
                s.total_sweeps = k;
                if fine.sweep() <= 1e-6 {
                    s.converged = true;
                    break;
                }
            }
        }
        return s;
    }
    start_estimate(fine);
    let mut levels = vec![Coarse::from_fine(fine)];
    while let Some(last) = levels.last_mut() {
        if last.unknowns <= COARSEST_UNKNOWNS {
            break;
        }
        let next = last.coarsen();
        levels.push(next);
    }
    let floor = rounding_floor(fine.border_range());
    // Changes of the last three cycles, newest first.
    let mut changes = [f64::INFINITY; 3];
    while s.iterations < max_iterations && remaining_error(&changes, floor) >= tolerance_m {
        let (change, sweeps, ok) = fine_cycle(fine, &mut levels);
        s.total_sweeps += sweeps;
        s.coarsest_failed |= !ok;
        changes = [f64::from(change), changes[0], changes[1]];
        s.iterations += 1;
    }
    s.last_change_m = if s.iterations == 0 { 0.0 } else { changes[0] };
    s.converged = !s.coarsest_failed && remaining_error(&changes, floor) < tolerance_m;
    s
}

/// The change below which a cycle may only be moving heights by their
/// `f32` rounding: sixteen times the largest border height's `f32` epsilon
/// (16 to 32 units in its last place; a converged cycle's five steps move
/// each by one to three units).
fn rounding_floor(range: (f32, f32)) -> f64 {
    let top = range.0.abs().max(range.1.abs());
    if top.is_finite() {
        16.0 * f64::from(top) * f64::from(f32::EPSILON)
    } else {
        0.0
    }
}

/// One W-cycle from the finest level; returns a bound of the largest change
/// of an unknown (the sum of the largest change of each step), the sweeps
/// done and whether every coarsest solve succeeded.
fn fine_cycle(fine: &mut Fine<'_>, levels: &mut [Coarse]) -> (f32, usize, bool) {
    let mut change = 0f32;
    for _ in 0..SMOOTHING_SWEEPS {
        change += fine.sweep();
    }
    let Some(first) = levels.first_mut() else {
        return (change, SMOOTHING_SWEEPS, true);
    };
    first.restrict_fine(fine);
    let (a, ok_a) = w_cycle(levels);
    let (b, ok_b) = w_cycle(levels);
    if let Some(first) = levels.first() {
        change += first.correct_fine(fine);
    }
    for _ in 0..SMOOTHING_SWEEPS {
        change += fine.sweep();
    }
    (change, a + b + 2 * SMOOTHING_SWEEPS, ok_a && ok_b)
}

/// One W-cycle on the coarse error equations from `levels[0]` down (each
/// coarser level is visited twice per visit of the one above); returns the
/// sweeps done and whether every coarsest solve succeeded.
fn w_cycle(levels: &mut [Coarse]) -> (usize, bool) {
    let Some((level, rest)) = levels.split_first_mut() else {
        return (0, true);
    };
    let Some(next) = rest.first_mut() else {
        return level.solve_coarsest();
    };
    for _ in 0..SMOOTHING_SWEEPS {
        level.sweep();
    }
    level.restrict(next);
    // Two cycles on the coarser error equation (its right-hand side stays).
    let (first, ok_first) = w_cycle(rest);
    let (second, ok_second) = w_cycle(rest);
    if let Some(next) = rest.first() {
        level.correct_from(next);
    }
    for _ in 0..SMOOTHING_SWEEPS {
        level.sweep();
    }
    (first + second + 2 * SMOOTHING_SWEEPS, ok_first && ok_second)
}

/// Estimated distance of the current iterate from the solution, from the last
/// changes (newest first) of a linearly converging iteration: change × ρ / (1 −
/// ρ), with the contraction ρ the larger of the last two ratios of successive
/// changes kept within [0.5, 0.99], doubled because early ratios underestimate
/// ρ. It is never below twice the last change. Infinite until three changes
/// are known; 0 once the changes have stopped shrinking (the last at least
/// half the one before) at most `floor`: the iteration is down to the
/// heights' `f32` rounding, which no cycle can beat.
fn remaining_error(changes: &[f64; 3], floor: f64) -> f64 {
    if changes[0] == 0.0 || (changes[0] <= floor && changes[0] >= 0.5 * changes[1]) {
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
