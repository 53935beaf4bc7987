//! Surface categorization after Sinapov et al.: a similarity between surfaces from the
//! recognizer's confusions, a hierarchy of categories by recursive normalized cuts (Shi & Malik),
//! and 2-D embeddings of the surfaces (classical MDS, ISOMAP) to plot them.
//!
//! The similarity comes from the confusion matrix rather than from feature distances because
//! that is what Sinapov et al. did and it asks the question the categorization is about: two
//! surfaces the recognizer cannot tell apart belong together, whatever the features' scales.
//! Matrices are `&[Vec<f64>]`, row-major and square.

use faer::{Mat, Side};
use serde::Serialize;

use crate::RecognizeError;
use crate::{SettingError, UsageError};

/// Checks that `m` is a non-empty, square, finite, non-negative, symmetric matrix; returns `n`.
fn check(m: &[Vec<f64>]) -> Result<usize, RecognizeError> {
    let n = m.len();
    if n == 0 {
        return Err(RecognizeError::Usage(UsageError::EmptyMatrix));
    }
    for (row, r) in m.iter().enumerate() {
        if r.len() != n {
            return Err(RecognizeError::Usage(UsageError::NotSquare {
                row,
                len: r.len(),
                n,
            }));
        }
        for (col, &value) in r.iter().enumerate() {
            if !value.is_finite() {
                return Err(RecognizeError::Usage(UsageError::NonFiniteEntry { row, col }));
            }
            if value < 0.0 {
                return Err(RecognizeError::Usage(UsageError::Negative { row, col, value }));
            }
        }
    }
    for (i, row) in m.iter().enumerate() {
        for (j, &a) in row.iter().enumerate().skip(i + 1) {
            // Relative tolerance: matrices built by symmetrising in floating point may differ
            // in the last bits.
            let b = m[j][i];
            if (a - b).abs() > 1e-9 * (1.0 + a.abs().max(b.abs())) {
                return Err(RecognizeError::Usage(UsageError::Asymmetric { row: i, col: j }));
            }
        }
    }
    Ok(n)
}

/// Similarity between classes from a confusion matrix (`counts[truth][predicted]`), after
/// Sinapov et al.: each row is turned into rates, the rates are symmetrised,
/// `S_ij = (R_ij + R_ji) / 2`, and the diagonal is set to 1.
///
/// Row rates rather than Sinapov's division by a fixed trial count, so that classes with
/// unequal numbers of test captures weigh alike (the two agree when counts are equal). The
/// diagonal is 1 as in the paper: it is not a confusion, and it keeps every degree positive so
/// that the normalized Laplacian exists. A class with no test decisions contributes only
/// through the other classes' confusions with it.
pub fn similarity_from_confusion(counts: &[Vec<u64>]) -> Result<Vec<Vec<f64>>, RecognizeError> {
    let n = counts.len();
    if n == 0 {
        return Err(RecognizeError::Usage(UsageError::EmptyMatrix));
    }
    let mut rates = vec![vec![0.0; n]; n];
    for (row, r) in counts.iter().enumerate() {
        if r.len() != n {
            return Err(RecognizeError::Usage(UsageError::NotSquare {
                row,
                len: r.len(),
                n,
            }));
        }
        let total: u64 = r.iter().sum();
        if total > 0 {
            for (rate, &c) in rates[row].iter_mut().zip(r) {
                *rate = c as f64 / total as f64;
            }
        }
    }
    Ok(square(n, 1.0, |i, j| 0.5 * (rates[i][j] + rates[j][i])))
}

/// An `n` × `n` matrix with `diagonal` on its diagonal and `off(i, j)` elsewhere.
fn square(n: usize, diagonal: f64, off: impl Fn(usize, usize) -> f64) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| if i == j { diagonal } else { off(i, j) })
                .collect()
        })
        .collect()
}

/// Distances for an embedding from a similarity in `[0, 1]`: `1 − S`, 0 on the diagonal.
pub fn distances_from_similarity(similarity: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, RecognizeError> {
    let n = check(similarity)?;
    Ok(square(n, 0.0, |i, j| (1.0 - similarity[i][j]).max(0.0)))
}

/// One bipartition by [`normalized_cut`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cut {
    /// One side, ascending indices into the similarity matrix.
    pub left: Vec<usize>,
    /// The other side, ascending.
    pub right: Vec<usize>,
    /// Shi & Malik's `Ncut = cut/assoc(A,V) + cut/assoc(B,V)`, in `[0, 2]`; 0 when the sides do
    /// not touch.
    pub ncut: f64,
}

/// Ncut of splitting `indices` into the members with `in_left` true and the rest.
fn ncut_value(w: &[Vec<f64>], indices: &[usize], in_left: &[bool]) -> f64 {
    let (mut cut, mut assoc_l, mut assoc_r) = (0.0, 0.0, 0.0);
    for (a, &i) in indices.iter().enumerate() {
        for (b, &j) in indices.iter().enumerate() {
            let wij = w[i][j];
            if in_left[a] {
                assoc_l += wij;
            } else {
                assoc_r += wij;
            }
            if in_left[a] && !in_left[b] {
                cut += wij;
            }
        }
    }
    let part = |assoc: f64| if assoc > 0.0 { cut / assoc } else { 0.0 };
    part(assoc_l) + part(assoc_r)
}

/// Splits the classes `indices` of `similarity` in two by Shi & Malik's normalized cut: the
/// eigenvector of the second-smallest eigenvalue of the normalized Laplacian
/// `I − D^{-1/2} W D^{-1/2}`, scaled back by `D^{-1/2}`, orders the classes, and the threshold
/// along that order with the smallest Ncut value splits them.
///
/// A class with no similarity to the others (degree 0) is cut off alone with Ncut 0.
pub fn normalized_cut(similarity: &[Vec<f64>], indices: &[usize]) -> Result<Cut, RecognizeError> {
    let n = check(similarity)?;
    let mut seen = vec![false; n];
    for &index in indices {
        if index >= n || seen[index] {
            return Err(RecognizeError::Usage(UsageError::BadIndex { index, n }));
        }
        seen[index] = true;
    }
    let m = indices.len();
    if m < 2 {
        return Err(RecognizeError::category_config(
            "a cut needs at least two classes",
        ));
    }
    let degree: Vec<f64> = indices
        .iter()
        .map(|&i| indices.iter().map(|&j| similarity[i][j]).sum())
        .collect();
    if let Some(a) = degree.iter().position(|&d| d <= 0.0) {
        let mut right: Vec<usize> = indices.to_vec();
        let isolated = right.remove(a);
        right.sort_unstable();
        return Ok(Cut {
            left: vec![isolated],
            right,
            ncut: 0.0,
        });
    }
    let inv_sqrt: Vec<f64> = degree.iter().map(|d| 1.0 / d.sqrt()).collect();
    let norm: f64 = degree.iter().sum::<f64>().sqrt();
    // D^{1/2}·1 is the Laplacian's eigenvector of eigenvalue 0 whatever W is. Adding 3·u·uᵀ
    // (eigenvalues of the normalized Laplacian lie in [0, 2]) moves it to the top, so the
    // smallest eigenvector left is the Fiedler vector even when 0 is a repeated eigenvalue
    // (several disconnected groups), where the solver's order among equal eigenvalues would
    // otherwise be arbitrary.
    let u: Vec<f64> = degree.iter().map(|d| d.sqrt() / norm).collect();
    let laplacian = Mat::from_fn(m, m, |a, b| {
        let identity = if a == b { 1.0 } else { 0.0 };
        identity - inv_sqrt[a] * similarity[indices[a]][indices[b]] * inv_sqrt[b] + 3.0 * u[a] * u[b]
    });
    let (values, vectors) = symmetric_eigen(&laplacian)?;
    let smallest = (0..m)
        .min_by(|&a, &b| values[a].total_cmp(&values[b]))
        .ok_or(RecognizeError::Usage(UsageError::EmptyMatrix))?;
    let y: Vec<f64> = (0..m).map(|a| vectors[(a, smallest)] * inv_sqrt[a]).collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| y[a].total_cmp(&y[b]).then(indices[a].cmp(&indices[b])));
    let mut best: Option<(f64, usize)> = None;
    let mut in_left = vec![false; m];
    for split in 1..m {
        in_left[order[split - 1]] = true;
        let value = ncut_value(similarity, indices, &in_left);
        if best.is_none_or(|(b, _)| value < b - 1e-12) {
            best = Some((value, split));
        }
    }
    let (ncut, split) = best.ok_or(RecognizeError::Usage(UsageError::EmptyMatrix))?;
    let mut left: Vec<usize> = order[..split].iter().map(|&a| indices[a]).collect();
    let mut right: Vec<usize> = order[split..].iter().map(|&a| indices[a]).collect();
    left.sort_unstable();
    right.sort_unstable();
    // The side holding the smallest index first, so the same matrix always prints the same tree.
    if right.first() < left.first() {
        std::mem::swap(&mut left, &mut right);
    }
    Ok(Cut { left, right, ncut })
}

/// When [`recursive_ncut`] stops splitting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StopRule {
    /// A set is kept whole when its best cut's Ncut value exceeds this (Sinapov: "fails to find
    /// a bipartition with a high score"). Ncut lies in `[0, 2]`; splitting a group of equally
    /// similar classes costs 1.
    pub max_ncut: f64,
    /// Sets with fewer members than this are not split (at least 2; Sinapov used 5).
    pub min_size: usize,
}

impl Default for StopRule {
    fn default() -> Self {
        Self {
            max_ncut: 0.5,
            min_size: 2,
        }
    }
}

/// A node of the category hierarchy.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CategoryTree {
    /// Classes in this category, ascending indices.
    pub members: Vec<usize>,
    /// Ncut value of the split into `children`, or of the rejected best split at a leaf of two
    /// or more members that met the size rule (`None` at a leaf that was not tried).
    pub ncut: Option<f64>,
    /// Two sub-categories, or none at a leaf.
    pub children: Vec<CategoryTree>,
}

impl CategoryTree {
    /// The leaves' member sets, left to right.
    pub fn leaves(&self) -> Vec<&[usize]> {
        if self.children.is_empty() {
            vec![&self.members]
        } else {
            self.children.iter().flat_map(CategoryTree::leaves).collect()
        }
    }

    /// Indented text, one category a line, classes by `names` (index when a name is missing).
    pub fn to_text(&self, names: &[String]) -> String {
        let mut out = String::new();
        self.write_text(names, 0, &mut out);
        out
    }

    fn write_text(&self, names: &[String], depth: usize, out: &mut String) {
        let list: Vec<String> = self
            .members
            .iter()
            .map(|&i| names.get(i).cloned().unwrap_or_else(|| i.to_string()))
            .collect();
        let ncut = match (self.ncut, self.children.is_empty()) {
            (Some(v), false) => format!("  [split, Ncut {v:.3}]"),
            (Some(v), true) => format!("  [kept, best Ncut {v:.3}]"),
            (None, _) => String::new(),
        };
        out.push_str(&format!("{}- {}{}\n", "  ".repeat(depth), list.join(", "), ncut));
        for child in &self.children {
            child.write_text(names, depth + 1, out);
        }
    }
}

/// Recursively bipartitions all classes of `similarity` by [`normalized_cut`] until `stop`
/// keeps a set whole or it has a single member.
pub fn recursive_ncut(similarity: &[Vec<f64>], stop: StopRule) -> Result<CategoryTree, RecognizeError> {
    let n = check(similarity)?;
    if stop.max_ncut.is_nan() || stop.max_ncut < 0.0 {
        return Err(RecognizeError::category_config(
            "max_ncut must be a non-negative number",
        ));
    }
    if stop.min_size < 2 {
        return Err(RecognizeError::category_config("min_size must be at least 2"));
    }
    split((0..n).collect(), similarity, stop)
}

fn split(members: Vec<usize>, w: &[Vec<f64>], stop: StopRule) -> Result<CategoryTree, RecognizeError> {
    if members.len() < stop.min_size {
        return Ok(CategoryTree {
            members,
            ncut: None,
            children: Vec::new(),
        });
    }
    let cut = normalized_cut(w, &members)?;
    if cut.ncut > stop.max_ncut {
        return Ok(CategoryTree {
            members,
            ncut: Some(cut.ncut),
            children: Vec::new(),
        });
    }
    let children = vec![split(cut.left, w, stop)?, split(cut.right, w, stop)?];
    Ok(CategoryTree {
        members,
        ncut: Some(cut.ncut),
        children,
    })
}

/// Classical (Torgerson) MDS: coordinates in `D` dimensions whose Euclidean distances best
/// match `distances`, from the top eigenvectors of the double-centred squared distances.
/// Each axis's sign is fixed so that its largest-magnitude coordinate is positive, so the same
/// input always gives the same picture.
pub fn classical_mds<const D: usize>(distances: &[Vec<f64>]) -> Result<Vec<[f64; D]>, RecognizeError> {
    let n = check(distances)?;
    if D == 0 {
        return Err(RecognizeError::category_config(
            "MDS needs at least one dimension",
        ));
    }
    let sq = |i: usize, j: usize| distances[i][j] * distances[i][j];
    let row_mean: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| sq(i, j)).sum::<f64>() / n as f64)
        .collect();
    let all_mean = row_mean.iter().sum::<f64>() / n as f64;
    // B = −½ J D² J, written out: −½ (d²_ij − mean_i − mean_j + mean).
    let b = Mat::from_fn(n, n, |i, j| {
        -0.5 * (sq(i, j) - row_mean[i] - row_mean[j] + all_mean)
    });
    let (values, vectors) = symmetric_eigen(&b)?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let mut out = vec![[0.0; D]; n];
    for (axis, &k) in order.iter().take(D).enumerate() {
        // Negative eigenvalues mean the distances are not Euclidean; those axes carry nothing.
        let scale = values[k].max(0.0).sqrt();
        let column = vectors.col(k);
        let flip = column
            .iter()
            .copied()
            .max_by(|a, b| a.abs().total_cmp(&b.abs()))
            .map_or(1.0, |v| if v < 0.0 { -1.0 } else { 1.0 });
        for (i, point) in out.iter_mut().enumerate() {
            point[axis] = flip * scale * column[i];
        }
    }
    Ok(out)
}

/// The eigenvalues and eigenvectors (as columns) of the symmetric matrix `a`, from its lower
/// triangle.
fn symmetric_eigen(a: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>), RecognizeError> {
    let eig = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| RecognizeError::category_config("the eigendecomposition did not converge"))?;
    let s = eig.S().column_vector();
    let values = (0..s.nrows()).map(|k| s[k]).collect();
    Ok((values, eig.U().to_owned()))
}

/// ISOMAP (Tenenbaum et al.): geodesic distances along the graph joining each point to its
/// `k` nearest neighbours (an edge when either end chose it), by Floyd–Warshall, embedded by
/// [`classical_mds`].
pub fn isomap<const D: usize>(distances: &[Vec<f64>], k: usize) -> Result<Vec<[f64; D]>, RecognizeError> {
    let geodesic = geodesic_distances(distances, k)?;
    classical_mds::<D>(&geodesic)
}

/// Shortest-path distances along the symmetrised `k`-nearest-neighbour graph of `distances`.
pub fn geodesic_distances(distances: &[Vec<f64>], k: usize) -> Result<Vec<Vec<f64>>, RecognizeError> {
    let n = check(distances)?;
    if k == 0 {
        return Err(RecognizeError::category_config("ISOMAP needs k ≥ 1 neighbours"));
    }
    let mut g = vec![vec![f64::INFINITY; n]; n];
    for (i, row) in g.iter_mut().enumerate() {
        row[i] = 0.0;
    }
    for i in 0..n {
        let mut others: Vec<usize> = (0..n).filter(|&j| j != i).collect();
        others.sort_by(|&a, &b| distances[i][a].total_cmp(&distances[i][b]).then(a.cmp(&b)));
        for &j in others.iter().take(k) {
            g[i][j] = distances[i][j];
            g[j][i] = distances[i][j];
        }
    }
    for via in 0..n {
        // Row `via` does not change while relaxing through `via` (g[via][via] = 0).
        let via_row = g[via].clone();
        for row in g.iter_mut() {
            let to_via = row[via];
            if to_via.is_infinite() {
                continue;
            }
            for (d, &onward) in row.iter_mut().zip(&via_row) {
                let through = to_via + onward;
                if through < *d {
                    *d = through;
                }
            }
        }
    }
    for (from, row) in g.iter().enumerate() {
        if let Some(to) = row.iter().position(|d| d.is_infinite()) {
            return Err(RecognizeError::Setting(SettingError::Disconnected {
                k,
                from,
                to,
            }));
        }
    }
    Ok(g)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Block-diagonal similarity: 1 inside blocks of the given sizes, `leak` between blocks,
    /// with block members interleaved so that index order alone does not give the answer.
    fn blocks(sizes: &[usize], leak: f64) -> (Vec<Vec<f64>>, Vec<usize>) {
        let n: usize = sizes.iter().sum();
        let mut block_of = Vec::new();
        let mut left = sizes.to_vec();
        while block_of.len() < n {
            for (b, l) in left.iter_mut().enumerate() {
                if *l > 0 {
                    block_of.push(b);
                    *l -= 1;
                }
            }
        }
        let w = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| if block_of[i] == block_of[j] { 1.0 } else { leak })
                    .collect()
            })
            .collect();
        (w, block_of)
    }

    fn members_of(block_of: &[usize], b: usize) -> Vec<usize> {
        (0..block_of.len()).filter(|&i| block_of[i] == b).collect()
    }

    #[test]
    fn ncut_splits_two_blocks_exactly() {
        let (w, block_of) = blocks(&[4, 3], 0.02);
        let cut = normalized_cut(&w, &(0..7).collect::<Vec<_>>()).unwrap();
        assert_eq!(cut.left, members_of(&block_of, 0));
        assert_eq!(cut.right, members_of(&block_of, 1));
        assert!(cut.ncut < 0.1, "{}", cut.ncut);
    }

    #[test]
    fn ncut_splits_disconnected_blocks_with_zero_value() {
        let (w, block_of) = blocks(&[3, 3], 0.0);
        let cut = normalized_cut(&w, &[0, 1, 2, 3, 4, 5]).unwrap();
        assert_eq!(cut.left, members_of(&block_of, 0));
        assert_eq!(cut.ncut, 0.0);
    }

    #[test]
    fn ncut_of_a_subset_uses_only_that_subset() {
        let (w, block_of) = blocks(&[2, 2, 2], 0.05);
        let subset: Vec<usize> = (0..6).filter(|&i| block_of[i] != 1).collect();
        let cut = normalized_cut(&w, &subset).unwrap();
        assert_eq!(cut.left, members_of(&block_of, 0));
        assert_eq!(cut.right, members_of(&block_of, 2));
    }

    #[test]
    fn recursive_cut_of_three_blocks_gives_three_leaves() {
        for leak in [0.0, 0.03] {
            let (w, block_of) = blocks(&[3, 4, 2], leak);
            let tree = recursive_ncut(&w, StopRule::default()).unwrap();
            let mut leaves: Vec<Vec<usize>> = tree.leaves().into_iter().map(<[usize]>::to_vec).collect();
            leaves.sort();
            let mut expected: Vec<Vec<usize>> = (0..3).map(|b| members_of(&block_of, b)).collect();
            expected.sort();
            // Splitting a block of equal similarities costs Ncut 1, above the threshold: the
            // three blocks are the leaves.
            assert_eq!(leaves, expected, "leak {leak}\n{}", tree.to_text(&[]));
        }
    }

    #[test]
    fn min_size_keeps_small_sets_whole() {
        let (w, _) = blocks(&[3, 4, 2], 0.01);
        let tree = recursive_ncut(
            &w,
            StopRule {
                max_ncut: 2.0,
                min_size: 10,
            },
        )
        .unwrap();
        assert!(tree.children.is_empty());
        assert_eq!(tree.members.len(), 9);
        assert_eq!(tree.ncut, None);
    }

    #[test]
    fn similarity_from_confusion_symmetrises_rates() {
        let c = vec![vec![8, 2, 0], vec![0, 4, 0], vec![1, 1, 2]];
        let s = similarity_from_confusion(&c).unwrap();
        assert_eq!(s[0][0], 1.0);
        assert!((s[0][1] - 0.5 * (0.2 + 0.0)).abs() < 1e-12);
        assert!((s[0][2] - 0.5 * (0.0 + 0.25)).abs() < 1e-12);
        assert!((s[1][2] - 0.5 * (0.0 + 0.25)).abs() < 1e-12);
        check(&s).unwrap();
        assert!(matches!(
            similarity_from_confusion(&[]),
            Err(RecognizeError::Usage(UsageError::EmptyMatrix))
        ));
        assert!(matches!(
            similarity_from_confusion(&[vec![1, 2], vec![3]]),
            Err(RecognizeError::Usage(UsageError::NotSquare { row: 1, .. }))
        ));
    }

    fn euclid(points: &[[f64; 2]]) -> Vec<Vec<f64>> {
        points
            .iter()
            .map(|a| {
                points
                    .iter()
                    .map(|b| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt())
                    .collect()
            })
            .collect()
    }

    #[test]
    fn classical_mds_recovers_planar_distances() {
        let points = [
            [0.0, 0.0],
            [3.0, 1.0],
            [-2.0, 4.0],
            [1.5, -2.5],
            [5.0, 5.0],
            [-1.0, -3.0],
        ];
        let d = euclid(&points);
        let y = classical_mds::<2>(&d).unwrap();
        let d2 = euclid(&y);
        for i in 0..points.len() {
            for j in 0..points.len() {
                assert!(
                    (d[i][j] - d2[i][j]).abs() < 1e-9,
                    "({i},{j}): {} vs {}",
                    d[i][j],
                    d2[i][j]
                );
            }
        }
    }

    #[test]
    fn isomap_unrolls_a_curve_where_mds_cannot() {
        // Three quarters of a circle: its straight-line distances fold the ends towards each
        // other, the geodesics along the curve do not.
        let n = 30;
        let points: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = 1.5 * std::f64::consts::PI * i as f64 / (n - 1) as f64;
                [t.cos(), t.sin()]
            })
            .collect();
        let d = euclid(&points);
        let monotone = |xs: &[f64]| xs.windows(2).all(|p| p[1] > p[0]) || xs.windows(2).all(|p| p[1] < p[0]);
        let y = isomap::<2>(&d, 2).unwrap();
        let first: Vec<f64> = y.iter().map(|p| p[0]).collect();
        assert!(monotone(&first), "{first:?}");
        // Evenly spaced along the arc: so are the ISOMAP coordinates, but for the end points'
        // second-neighbour shortcuts (a chord of two steps is 0.3 % shorter than two chords).
        let steps: Vec<f64> = first.windows(2).map(|p| (p[1] - p[0]).abs()).collect();
        let mid = steps[n / 2];
        for s in &steps {
            assert!((s - mid).abs() < 1e-2 * mid, "{steps:?}");
        }
        let flat = classical_mds::<2>(&d).unwrap();
        assert!(!monotone(&flat.iter().map(|p| p[0]).collect::<Vec<_>>()));
    }

    #[test]
    fn isomap_reports_a_disconnected_graph() {
        let points = [[0.0, 0.0], [0.1, 0.0], [10.0, 0.0], [10.1, 0.0]];
        assert!(matches!(
            isomap::<2>(&euclid(&points), 1),
            Err(RecognizeError::Setting(SettingError::Disconnected { k: 1, .. }))
        ));
        assert!(isomap::<2>(&euclid(&points), 2).is_ok());
        assert!(matches!(
            isomap::<2>(&euclid(&points), 0),
            Err(RecognizeError::Setting(SettingError::Config {
                of: "category parameter",
                ..
            }))
        ));
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let empty: Vec<Vec<f64>> = Vec::new();
        assert!(matches!(
            classical_mds::<2>(&empty),
            Err(RecognizeError::Usage(UsageError::EmptyMatrix))
        ));
        assert!(matches!(
            recursive_ncut(&empty, StopRule::default()),
            Err(RecognizeError::Usage(UsageError::EmptyMatrix))
        ));
        assert!(matches!(
            classical_mds::<2>(&[vec![0.0, 1.0], vec![1.0]]),
            Err(RecognizeError::Usage(UsageError::NotSquare {
                row: 1,
                len: 1,
                n: 2
            }))
        ));
        assert!(matches!(
            isomap::<2>(&[vec![0.0, f64::NAN], vec![f64::NAN, 0.0]], 1),
            Err(RecognizeError::Usage(UsageError::NonFiniteEntry {
                row: 0,
                col: 1
            }))
        ));
        assert!(matches!(
            normalized_cut(&[vec![1.0, -0.5], vec![-0.5, 1.0]], &[0, 1]),
            Err(RecognizeError::Usage(UsageError::Negative { row: 0, col: 1, .. }))
        ));
        assert!(matches!(
            recursive_ncut(&[vec![1.0, 0.2], vec![0.3, 1.0]], StopRule::default()),
            Err(RecognizeError::Usage(UsageError::Asymmetric { row: 0, col: 1 }))
        ));
        let w = vec![vec![1.0, 0.2], vec![0.2, 1.0]];
        assert!(matches!(
            normalized_cut(&w, &[0, 2]),
            Err(RecognizeError::Usage(UsageError::BadIndex { index: 2, n: 2 }))
        ));
        assert!(matches!(
            normalized_cut(&w, &[0, 0]),
            Err(RecognizeError::Usage(UsageError::BadIndex { index: 0, .. }))
        ));
        assert!(matches!(
            normalized_cut(&w, &[1]),
            Err(RecognizeError::Setting(SettingError::Config {
                of: "category parameter",
                ..
            }))
        ));
        for (max_ncut, min_size) in [(f64::NAN, 2), (0.5, 1)] {
            assert!(matches!(
                recursive_ncut(&w, StopRule { max_ncut, min_size }),
                Err(RecognizeError::Setting(SettingError::Config {
                    of: "category parameter",
                    ..
                }))
            ));
        }
    }

    #[test]
    fn isolated_class_is_cut_off_alone() {
        let w = vec![vec![0.0, 0.0, 0.0], vec![0.0, 1.0, 0.5], vec![0.0, 0.5, 1.0]];
        let cut = normalized_cut(&w, &[0, 1, 2]).unwrap();
        assert_eq!((cut.left, cut.right, cut.ncut), (vec![0], vec![1, 2], 0.0));
    }

    #[test]
    fn tree_text_names_classes() {
        let (w, _) = blocks(&[1, 1], 0.1);
        let tree = recursive_ncut(&w, StopRule::default()).unwrap();
        let text = tree.to_text(&["glass".to_owned(), "wood".to_owned()]);
        assert!(text.starts_with("- glass, wood  [split, Ncut"), "{text}");
        assert!(
            text.contains("\n  - glass\n") && text.contains("\n  - wood\n"),
            "{text}"
        );
    }
}
