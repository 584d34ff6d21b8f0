//! Minimum s–t cut by the Boykov–Kolmogorov max-flow algorithm.
//!
//! The graph cut of GrabCut (Rother et al. 2004) needs an exact min-cut of a pixel graph with
//! ~10⁵–10⁶ nodes and short augmenting paths; Boykov & Kolmogorov's algorithm ("An experimental
//! comparison of min-cut/max-flow algorithms", PAMI 2004) is the standard choice for such
//! grids: two search trees (from the source and from the sink) grow towards each other, an
//! augmentation saturates the bottleneck, and orphaned nodes are re-adopted instead of
//! rebuilding the trees from scratch.
//!
//! Arcs are stored in pairs (`2k` is `u → v`, `2k + 1` its reverse), so an arc's sister is
//! `a ^ 1`. Terminal capacities are folded into one signed number per node: positive is
//! residual capacity from the source, negative residual capacity to the sink. Source side is
//! "object" by the convention of the callers.
//!
//! The caller allocates: [`Graph::reset`] keeps every buffer, so an interactive session re-cuts
//! without reallocating.

use std::collections::VecDeque;

const NONE: u32 = u32::MAX;
const TERMINAL: u32 = u32::MAX - 1;
const ORPHAN: u32 = u32::MAX - 2;

/// A directed graph with terminal links, cut by [`Graph::maxflow`].
#[derive(Clone, Debug, Default)]
pub struct Graph {
    /// First outgoing arc of each node (`NONE` if none).
    first: Vec<u32>,
    /// Target node of each arc.
    head: Vec<u32>,
    /// Next outgoing arc of the same tail node.
    next: Vec<u32>,
    /// Residual capacity of each arc.
    cap: Vec<f32>,
    /// Capacities saved by [`Graph::save`].
    cap0: Vec<f32>,
    /// Signed terminal residual: > 0 from the source, < 0 to the sink.
    tr: Vec<f32>,
    /// Arc from a node to its parent in its search tree, or `NONE`/`TERMINAL`/`ORPHAN`.
    parent: Vec<u32>,
    /// Whether a node (with a parent) belongs to the sink tree.
    sink: Vec<bool>,
    /// Time stamp of the last distance-to-terminal computation (BK §3.2 heuristics).
    ts: Vec<u32>,
    /// Distance to the terminal at time `ts`.
    dist: Vec<u32>,
    /// Whether a node sits in the active queue.
    queued: Vec<bool>,
    active: VecDeque<u32>,
    orphans: VecDeque<u32>,
    time: u32,
    flow: f64,
}

impl Graph {
    /// An empty graph of `nodes` nodes, with room for `edges` edges.
    pub fn new(nodes: usize, edges: usize) -> Graph {
        let mut g = Graph::default();
        g.reset(nodes, edges);
        g
    }

    /// Clears all arcs and terminal links and resizes to `nodes` nodes, keeping allocations.
    pub fn reset(&mut self, nodes: usize, edges: usize) {
        self.first.clear();
        self.first.resize(nodes, NONE);
        self.tr.clear();
        self.tr.resize(nodes, 0.0);
        self.head.clear();
        self.next.clear();
        self.cap.clear();
        self.cap0.clear();
        self.head.reserve(2 * edges);
        self.next.reserve(2 * edges);
        self.cap.reserve(2 * edges);
        self.flow = 0.0;
    }

    /// Remembers the arc capacities, so a later cut of the same graph with new terminal links
    /// can skip rebuilding it ([`Graph::restore`]).
    pub fn save(&mut self) {
        self.cap0.clone_from(&self.cap);
    }

    /// Restores the saved arc capacities and clears terminal links and flow. Returns false
    /// (and changes nothing) if nothing was saved since the last [`Graph::reset`].
    pub fn restore(&mut self) -> bool {
        if self.cap.is_empty() || self.cap0.len() != self.cap.len() {
            return false;
        }
        self.cap.copy_from_slice(&self.cap0);
        self.tr.fill(0.0);
        self.flow = 0.0;
        true
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.first.len()
    }

    /// Adds the edge pair `u → v` with capacity `cap_uv` and `v → u` with `cap_vu` (both ≥ 0).
    pub fn add_edge(&mut self, u: usize, v: usize, cap_uv: f32, cap_vu: f32) {
        let a = self.head.len() as u32;
        self.head.push(v as u32);
        self.next.push(self.first[u]);
        self.cap.push(cap_uv);
        self.first[u] = a;
        self.head.push(u as u32);
        self.next.push(self.first[v]);
        self.cap.push(cap_vu);
        self.first[v] = a + 1;
    }

    /// Adds terminal capacities: `source` from the source to `v`, `sink` from `v` to the sink.
    pub fn add_tweights(&mut self, v: usize, source: f32, sink: f32) {
        let (mut cs, mut ct) = (source, sink);
        let delta = self.tr[v];
        if delta > 0.0 {
            cs += delta;
        } else {
            ct -= delta;
        }
        // The common part of both terminal links is flow already pushed through `v`.
        self.flow += f64::from(cs.min(ct));
        self.tr[v] = cs - ct;
    }

    /// Whether node `v` ended on the source side of the minimum cut (after [`Graph::maxflow`]).
    pub fn is_source(&self, v: usize) -> bool {
        self.parent[v] != NONE && !self.sink[v]
    }

    fn activate(&mut self, v: u32) {
        if !self.queued[v as usize] {
            self.queued[v as usize] = true;
            self.active.push_back(v);
        }
    }

    /// Computes the maximum flow (= minimum cut value) and leaves the cut in [`Graph::is_source`].
    pub fn maxflow(&mut self) -> f64 {
        let n = self.nodes();
        self.parent.clear();
        self.parent.resize(n, NONE);
        self.sink.clear();
        self.sink.resize(n, false);
        self.ts.clear();
        self.ts.resize(n, 0);
        self.dist.clear();
        self.dist.resize(n, 0);
        self.queued.clear();
        self.queued.resize(n, false);
        self.active.clear();
        self.orphans.clear();
        self.time = 0;
        for v in 0..n {
            if self.tr[v] != 0.0 {
                self.sink[v] = self.tr[v] < 0.0;
                self.parent[v] = TERMINAL;
                self.dist[v] = 1;
                self.activate(v as u32);
            }
        }
        while let Some(i) = self.active.pop_front() {
            self.queued[i as usize] = false;
            let iu = i as usize;
            if self.parent[iu] == NONE {
                continue;
            }
            // Growth stage: scan the neighbours of `i` for a free node or the other tree.
            let mut bridge = NONE;
            let mut a = self.first[iu];
            while a != NONE {
                let j = self.head[a as usize] as usize;
                let residual = if self.sink[iu] {
                    self.cap[(a ^ 1) as usize]
                } else {
                    self.cap[a as usize]
                };
                if residual > 0.0 {
                    if self.parent[j] == NONE {
                        self.sink[j] = self.sink[iu];
                        self.parent[j] = a ^ 1;
                        self.ts[j] = self.ts[iu];
                        self.dist[j] = self.dist[iu] + 1;
                        self.activate(j as u32);
                    } else if self.sink[j] != self.sink[iu] {
                        // The bridge is stored in the source → sink direction.
                        bridge = if self.sink[iu] { a ^ 1 } else { a };
                        break;
                    } else if self.ts[j] <= self.ts[iu] && self.dist[j] > self.dist[iu] {
                        // Shorter path heuristic (BK §3.2).
                        self.parent[j] = a ^ 1;
                        self.ts[j] = self.ts[iu];
                        self.dist[j] = self.dist[iu] + 1;
                    }
                }
                a = self.next[a as usize];
            }
            if bridge == NONE {
                continue;
            }
            self.time += 1;
            self.augment(bridge);
            self.adopt();
            // `i` may have more paths to offer: grow from it again first.
            if self.parent[iu] != NONE && !self.queued[iu] {
                self.queued[iu] = true;
                self.active.push_front(i);
            }
        }
        self.flow
    }

    fn augment(&mut self, bridge: u32) {
        let b = bridge as usize;
        // Bottleneck along source tree → bridge → sink tree.
        let mut delta = self.cap[b];
        let mut u = self.head[b ^ 1] as usize;
        loop {
            let p = self.parent[u];
            if p == TERMINAL {
                delta = delta.min(self.tr[u]);
                break;
            }
            delta = delta.min(self.cap[(p ^ 1) as usize]);
            u = self.head[p as usize] as usize;
        }
        let mut v = self.head[b] as usize;
        loop {
            let p = self.parent[v];
            if p == TERMINAL {
                delta = delta.min(-self.tr[v]);
                break;
            }
            delta = delta.min(self.cap[p as usize]);
            v = self.head[p as usize] as usize;
        }
        self.cap[b] -= delta;
        self.cap[b ^ 1] += delta;
        let mut u = self.head[b ^ 1] as usize;
        loop {
            let p = self.parent[u];
            if p == TERMINAL {
                self.tr[u] -= delta;
                if self.tr[u] <= 0.0 {
                    self.tr[u] = 0.0;
                    self.make_orphan(u);
                }
                break;
            }
            let (pa, pr) = ((p ^ 1) as usize, p as usize);
            self.cap[pa] -= delta;
            self.cap[pr] += delta;
            let next = self.head[pr] as usize;
            if self.cap[pa] <= 0.0 {
                self.cap[pa] = 0.0;
                self.make_orphan(u);
            }
            u = next;
        }
        let mut v = self.head[b] as usize;
        loop {
            let p = self.parent[v];
            if p == TERMINAL {
                self.tr[v] += delta;
                if self.tr[v] >= 0.0 {
                    self.tr[v] = 0.0;
                    self.make_orphan(v);
                }
                break;
            }
            let (pa, pr) = (p as usize, (p ^ 1) as usize);
            self.cap[pa] -= delta;
            self.cap[pr] += delta;
            let next = self.head[pa] as usize;
            if self.cap[pa] <= 0.0 {
                self.cap[pa] = 0.0;
                self.make_orphan(v);
            }
            v = next;
        }
        self.flow += f64::from(delta);
    }

    fn make_orphan(&mut self, v: usize) {
        self.parent[v] = ORPHAN;
        self.orphans.push_back(v as u32);
    }

    /// Adoption stage: find each orphan a new parent in its own tree or free it (BK §3.3).
    fn adopt(&mut self) {
        while let Some(i) = self.orphans.pop_front() {
            let iu = i as usize;
            let sink = self.sink[iu];
            let mut best = NONE;
            let mut best_d = u32::MAX;
            let mut a0 = self.first[iu];
            while a0 != NONE {
                let j0 = self.head[a0 as usize] as usize;
                // Residual from the candidate parent j towards i (source tree) or i → j (sink).
                let residual = if sink {
                    self.cap[a0 as usize]
                } else {
                    self.cap[(a0 ^ 1) as usize]
                };
                if residual > 0.0 && self.sink[j0] == sink && self.parent[j0] != NONE {
                    // Does j0 still reach a terminal? Walk up, using fresh time stamps.
                    let mut j = j0;
                    let mut d: u32 = 0;
                    loop {
                        if self.ts[j] == self.time {
                            d += self.dist[j];
                            break;
                        }
                        let a = self.parent[j];
                        d += 1;
                        if a == TERMINAL {
                            self.ts[j] = self.time;
                            self.dist[j] = 1;
                            break;
                        }
                        if a == ORPHAN || a == NONE {
                            d = u32::MAX;
                            break;
                        }
                        j = self.head[a as usize] as usize;
                    }
                    if d < u32::MAX {
                        if d < best_d {
                            best = a0;
                            best_d = d;
                        }
                        // Stamp the path so later walks stop early.
                        let mut j = j0;
                        while self.ts[j] != self.time {
                            self.ts[j] = self.time;
                            self.dist[j] = d;
                            d -= 1;
                            j = self.head[self.parent[j] as usize] as usize;
                        }
                    }
                }
                a0 = self.next[a0 as usize];
            }
            if best != NONE {
                self.parent[iu] = best;
                self.ts[iu] = self.time;
                self.dist[iu] = best_d + 1;
                continue;
            }
            // No parent: `i` becomes free; its tree neighbours may grow into it again.
            self.parent[iu] = NONE;
            let mut a0 = self.first[iu];
            while a0 != NONE {
                let j = self.head[a0 as usize] as usize;
                if self.sink[j] == sink && self.parent[j] != NONE {
                    let residual = if sink {
                        self.cap[a0 as usize]
                    } else {
                        self.cap[(a0 ^ 1) as usize]
                    };
                    if residual > 0.0 {
                        self.activate(j as u32);
                    }
                    let pj = self.parent[j];
                    if pj != TERMINAL && pj != ORPHAN && self.head[pj as usize] == i {
                        self.make_orphan(j);
                    }
                }
                a0 = self.next[a0 as usize];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tiny deterministic generator so the brute-force comparison covers many graphs.
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
        }
    }

    /// Cut value of a labelling (true = source side) by definition.
    fn cut_value(
        n: usize,
        edges: &[(usize, usize, f32, f32)],
        t: &[(f32, f32)],
        s: &[bool],
    ) -> f64 {
        let mut c = 0.0f64;
        for v in 0..n {
            c += f64::from(if s[v] { t[v].1 } else { t[v].0 });
        }
        for &(u, v, cuv, cvu) in edges {
            if s[u] && !s[v] {
                c += f64::from(cuv);
            }
            if s[v] && !s[u] {
                c += f64::from(cvu);
            }
        }
        c
    }

    #[test]
    fn maxflow_equals_brute_force_min_cut_on_random_graphs() {
        let mut rng = Lcg(7);
        for case in 0..300 {
            let n = 2 + case % 9;
            let mut edges = Vec::new();
            for u in 0..n {
                for v in u + 1..n {
                    if rng.next() < 0.5 {
                        let zero = rng.next() < 0.2;
                        let c1 = if zero { 0.0 } else { rng.next() * 3.0 };
                        edges.push((u, v, c1, rng.next() * 3.0));
                    }
                }
            }
            let t: Vec<(f32, f32)> = (0..n)
                .map(|_| {
                    let a = if rng.next() < 0.3 {
                        0.0
                    } else {
                        rng.next() * 4.0
                    };
                    let b = if rng.next() < 0.3 {
                        0.0
                    } else {
                        rng.next() * 4.0
                    };
                    (a, b)
                })
                .collect();
            let mut g = Graph::new(n, edges.len());
            for &(u, v, a, b) in &edges {
                g.add_edge(u, v, a, b);
            }
            for (v, &(a, b)) in t.iter().enumerate() {
                g.add_tweights(v, a, b);
            }
            let flow = g.maxflow();
            let labels: Vec<bool> = (0..n).map(|v| g.is_source(v)).collect();
            let best = (0..1u32 << n)
                .map(|m| {
                    let s: Vec<bool> = (0..n).map(|v| m >> v & 1 == 1).collect();
                    cut_value(n, &edges, &t, &s)
                })
                .fold(f64::INFINITY, f64::min);
            let ours = cut_value(n, &edges, &t, &labels);
            assert!(
                (flow - best).abs() < 1e-3 && (ours - best).abs() < 1e-3,
                "case {case}: flow {flow}, cut of labels {ours}, brute force {best}"
            );
        }
    }

    #[test]
    fn reset_reuses_the_graph() {
        let mut g = Graph::new(2, 1);
        g.add_edge(0, 1, 1.0, 0.0);
        g.add_tweights(0, 5.0, 0.0);
        g.add_tweights(1, 0.0, 5.0);
        assert!((g.maxflow() - 1.0).abs() < 1e-6);
        g.reset(2, 1);
        g.add_edge(0, 1, 2.0, 0.0);
        g.save();
        g.add_tweights(0, 5.0, 0.0);
        g.add_tweights(1, 0.0, 5.0);
        assert!((g.maxflow() - 2.0).abs() < 1e-6);
        // Restored: the edge has its full capacity again and the old terminal links are gone.
        assert!(g.restore());
        g.add_tweights(0, 0.5, 0.0);
        g.add_tweights(1, 0.0, 5.0);
        assert!((g.maxflow() - 0.5).abs() < 1e-6);
        g.reset(2, 1);
        assert!(!g.restore());
    }
}
