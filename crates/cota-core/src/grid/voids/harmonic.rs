//! The harmonic fill of one void component: a full multigrid start, then
//! multigrid cycles until the estimated remaining error is below the
//! tolerance (steps 2–4 of [`super`]).
//!
//! Multigrid after Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd
//! ed., SIAM 2000): full multigrid (§3, nested iteration), W-cycles on the
//! coarse levels, red–black Gauss–Seidel smoothing, Galerkin coarse
//! operators.

use super::coarse::Coarse;
use super::fine::Fine;
use super::interp::COARSEST_UNKNOWNS;

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

/// The harmonic fill of one component (the unknowns of `fine`): a full
/// multigrid start, then multigrid cycles until the estimated remaining
/// error is below the tolerance (metres), or the changes are down to the
/// `f32` rounding of the heights, or after `max_iterations` cycles; a
/// component too small to coarsen is solved directly. `on_cycle(cycles)`
/// after each cycle.
pub(super) fn harmonic(
    fine: &mut Fine<'_>,
    tolerance_m: f64,
    max_iterations: usize,
    on_cycle: &dyn Fn(usize),
) -> Solved {
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
    let mut levels = vec![Coarse::from_fine(fine)];
    while let Some(last) = levels.last() {
        if last.unknowns <= COARSEST_UNKNOWNS {
            break;
        }
        let next = last.coarsen();
        levels.push(next);
    }
    s.coarsest_failed |= !full_multigrid_start(fine, &mut levels);
    let floor = rounding_floor(fine.border_range());
    // Changes of the last three cycles, newest first.
    let mut changes = [f64::INFINITY; 3];
    while s.iterations < max_iterations && remaining_error(&changes, floor) >= tolerance_m {
        let (change, sweeps, ok) = fine_cycle(fine, &mut levels);
        s.total_sweeps += sweeps;
        s.coarsest_failed |= !ok;
        changes = [f64::from(change), changes[0], changes[1]];
        s.iterations += 1;
        on_cycle(s.iterations);
    }
    s.last_change_m = if s.iterations == 0 { 0.0 } else { changes[0] };
    s.converged = !s.coarsest_failed && remaining_error(&changes, floor) < tolerance_m;
    s
}

/// The change below which a cycle may only be moving heights by their
/// `f32` rounding: 32 times the largest border height's `f32` epsilon
/// (32 to 64 units in its last place; a converged cycle's five steps move
/// each by one to three units, and the change sums their largest moves:
/// measured 13 to 17 units on a 3601² tile's half-plane void).
fn rounding_floor(range: (f32, f32)) -> f64 {
    let top = range.0.abs().max(range.1.abs());
    if top.is_finite() {
        32.0 * f64::from(top) * f64::from(f32::EPSILON)
    } else {
        0.0
    }
}

/// The full multigrid start: the fine problem's right-hand side (the
/// border's pull, with the unknowns at 0) summed down every level, solved
/// exactly on the coarsest, then on each finer level interpolated (from the
/// unknowns only) and improved by one cycle, up to the fine unknowns.
/// Returns whether every coarsest solve succeeded.
fn full_multigrid_start(fine: &mut Fine<'_>, levels: &mut [Coarse]) -> bool {
    let Some(first) = levels.first_mut() else {
        return true;
    };
    first.restrict_fine(fine);
    for k in 1..levels.len() {
        let (lo, hi) = levels.split_at_mut(k);
        if let (Some(this), Some(next)) = (lo.last(), hi.first_mut()) {
            this.restrict(next);
        }
    }
    let mut ok = true;
    if let Some(last) = levels.last_mut() {
        ok &= last.solve_coarsest().1;
    }
    for k in (0..levels.len().saturating_sub(1)).rev() {
        let (lo, hi) = levels.split_at_mut(k + 1);
        if let (Some(this), Some(next)) = (lo.last_mut(), hi.first()) {
            this.start_from(next);
        }
        ok &= w_cycle(&mut levels[k..]).1;
    }
    if let Some(first) = levels.first() {
        first.start_fine(fine);
    }
    ok
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
    let (sweeps, ok) = w_cycle(levels);
    if let Some(first) = levels.first() {
        change += first.correct_fine(fine);
    }
    for _ in 0..SMOOTHING_SWEEPS {
        change += fine.sweep();
    }
    (change, sweeps + 2 * SMOOTHING_SWEEPS, ok)
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
