//! The direct solve of a multigrid level with few unknowns: a dense
//! Cholesky factorisation (the level's matrix is symmetric and, with a
//! Dirichlet border, positive definite).
//!
//! The coarsest-grid solve of Briggs, Henson & McCormick, *A Multigrid
//! Tutorial* (2nd ed., SIAM 2000).

/// Solves `A x = b` for the symmetric `n × n` matrix `a` (row-major), in
/// place: `b` becomes `x`. False (and `b` left half-way) when a pivot is not
/// positive, as rounding can make a barely definite matrix look.
pub(super) fn solve_dense(a: &mut [f64], b: &mut [f64], n: usize) -> bool {
    // A = L Lᵀ, L stored in the lower triangle of `a`.
    for i in 0..n {
        for j in 0..=i {
            let mut sum = a[i * n + j];
            for k in 0..j {
                sum -= a[i * n + k] * a[j * n + k];
            }
            if i == j {
                if sum <= 0.0 || !sum.is_finite() {
                    return false;
                }
                a[i * n + i] = sum.sqrt();
            } else {
                a[i * n + j] = sum / a[j * n + j];
            }
        }
    }
    // L y = b, then Lᵀ x = y, in place in `b`.
    for i in 0..n {
        let mut sum = b[i];
        for k in 0..i {
            sum -= a[i * n + k] * b[k];
        }
        b[i] = sum / a[i * n + i];
    }
    for i in (0..n).rev() {
        let mut sum = b[i];
        for k in i + 1..n {
            sum -= a[k * n + i] * b[k];
        }
        b[i] = sum / a[i * n + i];
    }
    true
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn solves_a_small_laplacian_and_refuses_an_indefinite_matrix() {
        // 2x - y = 1, -x + 2y = 1: x = y = 1.
        let (mut a, mut b) = (vec![2.0, -1.0, -1.0, 2.0], vec![1.0, 1.0]);
        assert!(solve_dense(&mut a, &mut b, 2));
        assert!((b[0] - 1.0).abs() < 1e-12 && (b[1] - 1.0).abs() < 1e-12);
        let (mut a, mut b) = (vec![1.0, 2.0, 2.0, 1.0], vec![1.0, 1.0]);
        assert!(!solve_dense(&mut a, &mut b, 2));
    }
}
