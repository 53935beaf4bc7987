//! Exact k-nearest-neighbour search in a k-d tree over [`super::Knn`]'s scaled training
//! points.
//!
//! Hand-written rather than a crate because the search must give bit-for-bit the answer of the
//! exhaustive scan: the same `f64` squared distances (same expression, same order of
//! summation), and equal distances ordered by training index. Crates such as `kiddo` fix the
//! dimension at compile time (here it is 5 for Nakano's features and up to ~130 for
//! histograms, known only from the data) and return equidistant neighbours in an unspecified
//! order, and a k-d tree small enough to check by reading is less risk than wrapping one.
//!
//! Exactness of the pruning: a node is skipped only when the lower bound of the distance to its
//! bounding box is strictly greater than the current k-th distance. The bound is a sum of the
//! per-dimension squared gaps to the box, in the same order as the distance itself (the same
//! partial sums, combined the same way: `lane_sum`); IEEE
//! rounding is monotone, so each computed gap term is at most the computed term of any point in
//! the box, and the computed sum of the gaps at most the computed distance. A skipped point is
//! therefore strictly farther than the k-th neighbour and could not have entered the answer,
//! even through a tie on distance (ties are never pruned).

/// Rows per leaf: small enough that the leaf scans stay short, large enough that the tree's
/// own overhead (bounds, recursion) stays below the distances it saves.
const LEAF: usize = 16;

/// Independent partial sums in [`lane_sum`].
const LANES: usize = 4;

/// `Σᵢ term(i)` for `i < len`, term i added to partial sum `i mod 4` in increasing i, the
/// four combined as `(s₀ + s₁) + (s₂ + s₃)`: one order of summation for the distance and its
/// box bound, so the bound stays below the distance (each partial sum is monotone in its
/// terms). A single running sum made every distance wait on the previous addition: with the
/// histograms' 130 features that latency was most of a k-NN's training time.
#[inline(always)]
fn lane_sum(len: usize, term: impl Fn(usize) -> f64) -> f64 {
    let mut lanes = [-0.0; LANES];
    let whole = len - len % LANES;
    for base in (0..whole).step_by(LANES) {
        for (k, lane) in lanes.iter_mut().enumerate() {
            *lane += term(base + k);
        }
    }
    for (k, lane) in lanes.iter_mut().enumerate().take(len - whole) {
        *lane += term(whole + k);
    }
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
}

/// Squared Euclidean distance, the one expression every search uses, so that the tree and the
/// exhaustive scan compare exactly the same numbers.
#[inline]
pub(super) fn squared_distance(p: &[f64], q: &[f64]) -> f64 {
    let len = p.len().min(q.len());
    let (p, q) = (&p[..len], &q[..len]);
    lane_sum(len, |i| (p[i] - q[i]) * (p[i] - q[i]))
}

/// The best `k` candidates so far, nearest first under the order (distance, training index).
#[derive(Debug)]
pub(super) struct Best {
    k: usize,
    found: Vec<(f64, usize)>,
}

impl Best {
    pub(super) fn new(k: usize) -> Self {
        Self {
            k,
            found: Vec::with_capacity(k + 1),
        }
    }

    /// Distance a candidate must not exceed to matter; `+∞` until `k` are found.
    #[inline]
    fn bound(&self) -> f64 {
        if self.found.len() < self.k {
            f64::INFINITY
        } else {
            self.found.last().map_or(f64::INFINITY, |w| w.0)
        }
    }

    /// Offers training point `index` at squared distance `d`.
    #[inline]
    pub(super) fn offer(&mut self, d: f64, index: usize) {
        let before = |(bd, bi): &(f64, usize)| bd.total_cmp(&d).then(bi.cmp(&index)).is_lt();
        if self.found.len() == self.k {
            match self.found.last() {
                Some(w) if before(w) => return,
                _ => {}
            }
        }
        let at = self.found.partition_point(before);
        self.found.insert(at, (d, index));
        self.found.truncate(self.k);
    }

    /// Forgets the candidates, keeping the buffer: a new search allocates nothing.
    pub(super) fn clear(&mut self) {
        self.found.clear();
    }

    /// The training indices found, nearest first, without giving up the buffer.
    pub(super) fn indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.found.iter().map(|&(_, i)| i)
    }

    /// The training indices found, nearest first.
    pub(super) fn into_indices(self) -> Vec<usize> {
        self.found.into_iter().map(|(_, i)| i).collect()
    }
}

/// A node covers rows `start..end` of the tree's reordered points; its children split them at
/// the median of one dimension.
#[derive(Debug, Clone)]
struct Node {
    start: usize,
    end: usize,
    /// Children, `None` for a leaf.
    children: Option<(usize, usize)>,
}

/// A k-d tree: the training rows reordered so that every node's rows are contiguous, each
/// node's bounding box, and the training index of every row.
#[derive(Debug, Clone)]
pub(super) struct KdTree {
    dim: usize,
    points: Vec<f64>,
    index: Vec<usize>,
    nodes: Vec<Node>,
    /// Per node, `dim` lower then `dim` upper bounds.
    bounds: Vec<f64>,
}

impl KdTree {
    /// Builds the tree over `points` (row-major, `dim` per row): splits at the median of the
    /// widest dimension until at most [`LEAF`] rows, or only identical rows, remain.
    pub(super) fn new(points: &[f64], dim: usize) -> Self {
        let n = points.len().checked_div(dim).unwrap_or(0);
        let mut order: Vec<usize> = (0..n).collect();
        let mut tree = Self {
            dim,
            points: Vec::new(),
            index: Vec::new(),
            nodes: Vec::new(),
            bounds: Vec::new(),
        };
        if n > 0 {
            tree.build(points, &mut order, 0, n);
        }
        tree.points = order
            .iter()
            .flat_map(|&i| &points[i * dim..(i + 1) * dim])
            .copied()
            .collect();
        tree.index = order;
        tree
    }

    /// Adds the node over `order[start..end]` and its subtree; returns its id.
    fn build(&mut self, points: &[f64], order: &mut [usize], start: usize, end: usize) -> usize {
        let dim = self.dim;
        let id = self.nodes.len();
        self.nodes.push(Node {
            start,
            end,
            children: None,
        });
        let at = self.bounds.len();
        self.bounds.extend(
            std::iter::repeat_n(f64::INFINITY, dim).chain(std::iter::repeat_n(f64::NEG_INFINITY, dim)),
        );
        for &i in &order[start..end] {
            for (j, &v) in points[i * dim..(i + 1) * dim].iter().enumerate() {
                let lo = &mut self.bounds[at + j];
                *lo = lo.min(v);
                let hi = &mut self.bounds[at + dim + j];
                *hi = hi.max(v);
            }
        }
        if end - start <= LEAF {
            return id;
        }
        let (split, spread) = (0..dim)
            .map(|j| (j, self.bounds[at + dim + j] - self.bounds[at + j]))
            .fold((0, 0.0), |best, c| if c.1 > best.1 { c } else { best });
        if spread <= 0.0 {
            // All rows identical: nothing to split, one leaf scans them in order.
            return id;
        }
        let mid = start + (end - start) / 2;
        order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            points[a * dim + split].total_cmp(&points[b * dim + split])
        });
        let left = self.build(points, order, start, mid);
        let right = self.build(points, order, mid, end);
        self.nodes[id].children = Some((left, right));
        id
    }

    /// Lower bound of the squared distance from `q` to any row of `node` (see the module
    /// documentation for why it never exceeds a computed distance).
    #[inline]
    fn box_bound(&self, node: usize, q: &[f64]) -> f64 {
        let at = node * 2 * self.dim;
        let lo = &self.bounds[at..at + self.dim];
        let hi = &self.bounds[at + self.dim..at + 2 * self.dim];
        let len = q.len().min(self.dim);
        lane_sum(len, |i| {
            let (v, l, h) = (q[i], lo[i], hi[i]);
            let gap = if v < l {
                l - v
            } else if v > h {
                v - h
            } else {
                0.0
            };
            gap * gap
        })
    }

    /// Offers to `best` every row that could be among the `k` nearest to `q` (scaled).
    pub(super) fn search(&self, q: &[f64], best: &mut Best) {
        if !self.nodes.is_empty() {
            let bound = self.box_bound(0, q);
            self.visit(0, bound, q, best);
        }
    }

    fn visit(&self, node: usize, bound: f64, q: &[f64], best: &mut Best) {
        if bound > best.bound() {
            return;
        }
        let n = &self.nodes[node];
        match n.children {
            None => {
                let rows = self.points[n.start * self.dim..n.end * self.dim].chunks_exact(self.dim);
                for (p, &i) in rows.zip(&self.index[n.start..n.end]) {
                    best.offer(squared_distance(p, q), i);
                }
            }
            Some((left, right)) => {
                let (bl, br) = (self.box_bound(left, q), self.box_bound(right, q));
                if bl <= br {
                    self.visit(left, bl, q, best);
                    self.visit(right, br, q, best);
                } else {
                    self.visit(right, br, q, best);
                    self.visit(left, bl, q, best);
                }
            }
        }
    }
}
