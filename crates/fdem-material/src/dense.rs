//! Solving the small linear systems of a return mapping (at most 4×4),
//! on the stack, by Gaussian elimination with partial pivoting.

/// Largest system solved.
pub const MAX: usize = 4;

/// Solves `g x = f` for the leading `n × n` block; `None` when singular
/// (or `n` is 0 or above [`MAX`]).
pub fn solve(g: [[f64; MAX]; MAX], f: [f64; MAX], n: usize) -> Option<[f64; MAX]> {
    // one copy per size, so that the loops have constant bounds and unroll;
    // the arithmetic, and so the result, is the same for every size
    match n {
        1 => solve_n::<1>(g, f),
        2 => solve_n::<2>(g, f),
        3 => solve_n::<3>(g, f),
        4 => solve_n::<4>(g, f),
        _ => None,
    }
}

/// [`solve`] for the leading `N × N` block.
#[inline(always)]
fn solve_n<const N: usize>(mut g: [[f64; MAX]; MAX], mut f: [f64; MAX]) -> Option<[f64; MAX]> {
    let scale = (0..N).flat_map(|i| (0..N).map(move |j| (i, j))).map(|(i, j)| g[i][j].abs()).fold(0.0, f64::max);
    if scale == 0.0 {
        return None;
    }
    for col in 0..N {
        let piv = (col..N).max_by(|&a, &b| g[a][col].abs().total_cmp(&g[b][col].abs()))?;
        if g[piv][col].abs() <= 1e-13 * scale {
            return None;
        }
        g.swap(col, piv);
        f.swap(col, piv);
        for row in col + 1..N {
            let m = g[row][col] / g[col][col];
            for k in col..N {
                g[row][k] -= m * g[col][k];
            }
            f[row] -= m * f[col];
        }
    }
    let mut x = [0.0; MAX];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| g[row][k] * x[k]).sum();
        x[row] = (f[row] - s) / g[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_and_detects_singular() {
        let g = [[0.0, 2.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0], [0.0, 0.0, 3.0, 1.0], [0.0, 0.0, 1.0, 2.0]];
        let x = solve(g, [4.0, 3.0, 5.0, 5.0], 4).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14);
        assert!((x[2] - 1.0).abs() < 1e-14 && (x[3] - 2.0).abs() < 1e-14);
        let s = [[1.0, 2.0, 0.0, 0.0], [2.0, 4.0, 0.0, 0.0], [0.0; 4], [0.0; 4]];
        assert!(solve(s, [1.0, 2.0, 0.0, 0.0], 2).is_none());
    }
}
