//! Opening mesh edges into interfaces by duplicating nodes.
//!
//! Given a set of "cut" edges, every node is split into one copy per sector
//! of its star, where a sector is a maximal fan of its elements connected
//! across uncut edges. A node on the interior of a cut line gets two copies,
//! a crossing of two lines four, the tip of a line (one cut edge at an
//! interior node) stays whole. The first sector (the one holding the
//! smallest element id) keeps the original id, so untouched ids stay stable;
//! new nodes are appended and their parent is published.

use crate::csr::Csr;
use crate::node_elements;

/// Splits `triangles` (edited in place) along `cut` edges (node pairs, any
/// order). Returns the parent node of every appended node: node
/// `n_nodes + k` is a copy of `parents[k]`.
pub fn split_along_edges(n_nodes: usize, triangles: &mut [[u32; 3]], cut: &[[u32; 2]]) -> Vec<u32> {
    let mut cut: Vec<[u32; 2]> = cut.iter().map(|&[a, b]| [a.min(b), a.max(b)]).collect();
    cut.sort_unstable();
    cut.dedup();
    let is_cut = |a: u32, b: u32| cut.binary_search(&[a.min(b), a.max(b)]).is_ok();
    let mut on_cut = vec![false; n_nodes];
    for &[a, b] in &cut {
        on_cut[a as usize] = true;
        on_cut[b as usize] = true;
    }
    let star: Csr = node_elements(n_nodes, triangles);
    let mut parents = Vec::new();
    let mut next = n_nodes as u32;
    // (element, local) replacements, applied after all stars are read
    let mut renames: Vec<(u32, u8, u32)> = Vec::new();
    let mut parent = Vec::<usize>::new();
    for p in 0..n_nodes {
        if !on_cut[p] {
            continue;
        }
        let items = star.row(p);
        let k = items.len();
        parent.clear();
        parent.extend(0..k);
        fn find(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        // join elements of the star that share an uncut edge (p, q)
        for i in 0..k {
            let (ei, li) = ((items[i] / 3) as usize, (items[i] % 3) as usize);
            let ti = triangles[ei];
            for q in [ti[(li + 1) % 3], ti[(li + 2) % 3]] {
                if is_cut(p as u32, q) {
                    continue;
                }
                for j in i + 1..k {
                    let ej = (items[j] / 3) as usize;
                    if triangles[ej].contains(&q) {
                        let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                        if ri != rj {
                            parent[ri.max(rj)] = ri.min(rj);
                        }
                    }
                }
            }
        }
        // sectors in order of their smallest element (items are sorted by element)
        let mut copy_of_root: Vec<(usize, u32)> = Vec::new();
        for i in 0..k {
            let r = find(&mut parent, i);
            let id = match copy_of_root.iter().find(|(root, _)| *root == r) {
                Some(&(_, id)) => id,
                None => {
                    let id = if copy_of_root.is_empty() {
                        p as u32
                    } else {
                        parents.push(p as u32);
                        next += 1;
                        next - 1
                    };
                    copy_of_root.push((r, id));
                    id
                }
            };
            if id != p as u32 {
                renames.push((items[i] / 3, (items[i] % 3) as u8, id));
            }
        }
    }
    for (e, l, id) in renames {
        triangles[e as usize][l as usize] = id;
    }
    parents
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3×3 nodes, 2×2 cells, right diagonals.
    fn grid() -> Vec<[u32; 3]> {
        let id = |i: u32, j: u32| j * 3 + i;
        let mut t = Vec::new();
        for j in 0..2 {
            for i in 0..2 {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        t
    }

    #[test]
    fn cut_through_the_middle_splits_two_bodies() {
        // vertical line x = 1 from bottom (node 1) to top (node 7)
        let mut t = grid();
        let parents = split_along_edges(9, &mut t, &[[1, 4], [4, 7]]);
        assert_eq!(parents, vec![1, 4, 7]);
        // no element left of the cut shares a node with one right of it
        let left: Vec<_> = t.iter().filter(|tri| tri.iter().all(|&v| v != 2 && v != 5 && v != 8)).collect();
        let right: Vec<_> = t.iter().filter(|tri| tri.iter().any(|&v| v == 2 || v == 5 || v == 8)).collect();
        for l in &left {
            for r in &right {
                assert!(l.iter().all(|v| !r.contains(v)), "{l:?} {r:?}");
            }
        }
    }

    #[test]
    fn crack_tip_inside_stays_whole() {
        // a cut from the bottom edge (node 1) to the centre (node 4): node 1
        // splits (boundary), node 4 is the tip and does not
        let mut t = grid();
        let parents = split_along_edges(9, &mut t, &[[1, 4]]);
        assert_eq!(parents, vec![1]);
    }

    #[test]
    fn crossing_cuts_give_four_copies() {
        let mut t = grid();
        let parents = split_along_edges(9, &mut t, &[[1, 4], [4, 7], [3, 4], [4, 5]]);
        assert_eq!(parents.iter().filter(|&&p| p == 4).count(), 3);
    }
}
