//! Solving the small linear systems of a return mapping (at most 4×4),
//! on the stack, by Gaussian elimination with partial pivoting.

/// Largest system solved.
pub const MAX: usize = 4;

/// Solves `g x = f` for the leading `n × n` block; `None` when singular.
pub fn solve(mut g: [[f64; MAX]; MAX], mut f: [f64; MAX], n: usize) -> Option<[f64; MAX]> {
    let scale = (0..n).flat_map(|i| (0..n).map(move |j| (i, j))).map(|(i, j)| g[i][j].abs()).fold(0.0, f64::max);
    if scale == 0.0 {
        return None;
    }
    for col in 0..n {
        let piv = (col..n).max_by(|&a, &b| g[a][col].abs().total_cmp(&g[b][col].abs()))?;
        if g[piv][col].abs() <= 1e-13 * scale {
            return None;
        }
        g.swap(col, piv);
        f.swap(col, piv);
        for row in col + 1..n {
            let m = g[row][col] / g[col][col];
            for k in col..n {
                g[row][k] -= m * g[col][k];
            }
            f[row] -= m * f[col];
        }
    }
    let mut x = [0.0; MAX];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| g[row][k] * x[k]).sum();
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
