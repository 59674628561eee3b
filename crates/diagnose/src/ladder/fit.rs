//! The ladder's fits: the normal equations of `[Y | E]` about one linearization point
//! ([`Data`]), the description and its prior ([`Problem`]), one fit's system with its trust
//! region and point-mass reduction ([`System`]), and the held-out improvement of a fit.

use super::*;

/// Normal equations of `[Y | E]` about one linearization point: the training data summed,
/// the held-out data per block.
pub(super) struct Data {
    /// Joints.
    pub(super) n: usize,
    /// The model parameters the linearized columns were built about.
    pub(super) theta_lin: DVector<f64>,
    pub(super) variants: Vec<Variant>,
    pub(super) offsets: Vec<usize>,
    /// The training data's blocks (the description test reads them).
    pub(super) folds: Folds,
    pub(super) train: physid_ident::NormalEquations,
    pub(super) held: Vec<physid_ident::NormalEquations>,
}

impl Data {
    /// Columns of every variant about the model parameters `theta`.
    pub(super) fn build(
        stage: &Stage,
        variants: &[Variant],
        theta: &DVector<f64>,
        blocks: usize,
    ) -> Data {
        let model = stage.model;
        let ms = stage.opts.min_speed;
        let (t, v) = (stage.train, stage.validate);
        // Training and held-out columns are independent: built side by side, each about
        // `theta` on the stage's processing of its logged torques.
        let (train, held) = rayon::join(
            || {
                let ctx = stage.ctx_train.about(theta, t);
                Folds::build(&ctx, t, 0..t.len(), variants.to_vec(), 2, &[], ms)
            },
            || {
                let ctx = stage.ctx_val.about(theta, v);
                Folds::build(&ctx, v, 0..v.len(), variants.to_vec(), blocks, &[], ms)
            },
        );
        Data {
            n: model.dof(),
            theta_lin: theta.clone(),
            variants: variants.to_vec(),
            offsets: train.offsets.clone(),
            train: train.sum_except(usize::MAX),
            folds: train,
            held: held.blocks,
        }
    }

    /// How far the model parameters `theta` move the predicted torques from those of the
    /// point the columns were built about, relative: `‖Y (θ − θ_lin)‖ / ‖Y θ_lin‖` over the
    /// training samples and joints (from the normal equations' `YᵀY`).
    pub(super) fn moved_from(&self, theta: &DVector<f64>) -> f64 {
        let p0 = self.theta_lin.len();
        let yty = self.train.yty.view((0, 0), (p0, p0));
        let d = theta - &self.theta_lin;
        let at = self.theta_lin.dot(&(yty * &self.theta_lin));
        (d.dot(&(yty * &d)) / at).sqrt()
    }

    /// The variant's index.
    pub(super) fn index(&self, v: &Variant) -> usize {
        self.variants
            .iter()
            .position(|w| w == v)
            .expect("an offered variant")
    }
}

/// The fixed parts of every fit: the description, its prior, the data's weight.
pub(super) struct Problem<'a> {
    pub(super) stage: &'a Stage<'a>,
    pub(super) theta_d: DVector<f64>,
    pub(super) prior: DMatrix<f64>,
    /// The prior's part from the stated relative uncertainty alone (the information of a
    /// baseline or a sidecar left out): the region the base may move in is measured by it, as
    /// run-to-run differences of a real robot exceed what one run's information allows.
    pub(super) stated: DMatrix<f64>,
    /// `P θ_d` and `P_ε θ_d`: the prior's pull towards the description.
    pub(super) prior_g: DVector<f64>,
    pub(super) stated_g: DVector<f64>,
    pub(super) weight: f64,
    /// The squared radius of the description's stated uncertainty: the `χ²` quantile, over the
    /// parameters the prior covers, exceeded with probability [`OUTSIDE`]; infinite when the
    /// prior carries the information of data (a baseline's, a sidecar's): a prior that grows
    /// with the data is not overrun by them.
    pub(super) radius2: f64,
}

/// The largest relative move of the predicted torques ([`Data::moved_from`]) after which a
/// step keeps the columns built about the previous point. A linearized column (a gain's `Y θ`,
/// a tilt's, a delay's, a compliance's deflection) built about `θ_lin` differs from one about
/// `θ`, to first order, by the same column of `θ − θ_lin`: a move of 2 % changes an effect's
/// predicted torque by about 2 % of itself. On the real KUKA (run 3 against runs 1+2's
/// identification) the three steps after the first moved the torques by 0.15 %, 1.3 % and
/// 0.22 %, and rebuilding about them changed the held-out mean square by less than 10⁻⁶,
/// 10⁻⁶ and 7·10⁻⁴ relative.
pub(super) const LINEARIZATION_TRUST: f64 = 0.02;

/// Probability that a description drawn from its stated uncertainty lies outside the region
/// the ladder's base may move in.
pub(super) const OUTSIDE: f64 = 1e-3;

/// A chosen body step reads as a payload (renamed a change by `name_changes` when it is not one).
pub(super) const PAYLOAD: &str = "payload";
/// A body step not chosen: what it reads as is not known.
pub(super) const UNREAD: &str = "payload or change";

/// A fit: the parameters over `cols` (model columns, then the chosen effects').
pub(super) struct Fit {
    pub(super) cols: Vec<usize>,
    pub(super) w: DVector<f64>,
    /// The posterior covariance's diagonal over `cols` (for standard errors).
    pub(super) var: Vec<f64>,
    /// Over `cols`: an explanation's column the data do not see at all (zero on every sample:
    /// the mass of a body whose frame origin lies on every joint axis before it), whose value
    /// and variance only the ridge sets.
    pub(super) unseen: Vec<bool>,
}

impl Problem<'_> {
    /// `min w·‖Z x − τ‖² + (x_Y − θ_d)ᵀ (P + (λ − 1) P_ε) (x_Y − θ_d)` over the model's columns
    /// and the chosen effects', friction fixed at the description's unless re-identified (`P`
    /// the prior, `P_ε` its stated-uncertainty part: the Lagrangian of the prior fit confined
    /// to the stated region); `λ = 1` unless that
    /// leaves the description's parameters outside their stated uncertainty
    /// (`(x_Y − θ_d)ᵀ P_ε (x_Y − θ_d) > r²`, [`Problem::radius2`]), then the `λ ≥ 1` that puts them
    /// on its edge. A Gaussian prior alone yields to any gap given data enough (a 2.5 kg payload
    /// on a 0.3 kg link is eighty standard deviations away, yet ten thousand samples outweigh
    /// them): the description "within its uncertainty" must stay within it, so that what lies
    /// beyond is left for the explanations to claim.
    pub(super) fn fit(&self, data: &Data, set: &[Explanation]) -> Fit {
        let system = self.system(data, set);
        let at_one = system.solve(1.0);
        if self.distance2(&at_one) <= self.radius2 {
            return system.with_variance(at_one, 1.0);
        }
        // The distance falls as λ grows: bisection on ln λ.
        let (mut lo, mut hi) = (0.0_f64, 30.0_f64);
        let mut best = (system.solve(hi.exp()), hi.exp());
        for _ in 0..48 {
            let mid = 0.5 * (lo + hi);
            let w = system.solve(mid.exp());
            if self.distance2(&w) <= self.radius2 {
                hi = mid;
                best = (w, mid.exp());
            } else {
                lo = mid;
            }
        }
        system.with_variance(best.0, best.1)
    }

    /// The squared Mahalanobis distance of a fit's model parameters from the description,
    /// under the stated uncertainty.
    pub(super) fn distance2(&self, w: &DVector<f64>) -> f64 {
        let p0 = self.theta_d.len();
        let dx = w.rows(0, p0) - &self.theta_d;
        dx.dot(&(&self.stated * &dx))
    }

    /// The normal equations of a fit over the columns `set` frees, the prior apart.
    pub(super) fn system(&self, data: &Data, set: &[Explanation]) -> System<'_> {
        let p0 = self.theta_d.len();
        let l = self.stage.model.layout();
        let n = self.stage.model.dof();
        let mut cols: Vec<usize> = (0..p0).collect();
        let mut signed = vec![];
        let mut effect_terms = vec![];
        let mut point_masses = vec![];
        for e in set {
            if let Some(v) = e.variant() {
                let at = data.offsets[data.index(&v)];
                let width = v.kind.columns(n);
                if let Explanation::PointMass(_, c) = e {
                    point_masses.push((cols.len(), *c));
                } else if anchor::signed(v.kind) {
                    signed.extend(cols.len()..cols.len() + width);
                }
                if !v.kind.is_body_change() {
                    effect_terms.extend(cols.len()..cols.len() + width);
                }
                cols.extend(at..at + width);
            }
        }
        let fixed: Vec<usize> = if set.contains(&Explanation::Friction) {
            vec![]
        } else {
            (l.viscous_col..l.len).collect()
        };
        let m = cols.len();
        let ne = &data.train;
        let h = DMatrix::from_fn(m, m, |i, j| self.weight * ne.yty[(cols[i], cols[j])]);
        let g = DVector::from_fn(m, |i, _| self.weight * ne.ytt[cols[i]]);
        let aliased = aliased(&h, effect_terms);
        let free: Vec<usize> = (0..m)
            .filter(|i| !fixed.contains(&cols[*i]) && !aliased.contains(i))
            .collect();
        let nonneg = free_positions(&free, &signed);
        let (reduce, nonneg) = point_mass_reduction(&free, &point_masses, nonneg);
        System {
            cols,
            h,
            g,
            prior: &self.prior,
            prior_g: &self.prior_g,
            stated: &self.stated,
            stated_g: &self.stated_g,
            theta_d: &self.theta_d,
            nonneg,
            reduce,
            fixed,
            free,
        }
    }
}

/// A column whose residual curvature, after the columns tested before it (their Gram matrix
/// `h`), is below this fraction of its own lies in their span.
pub(super) const ALIASED: f64 = 1e-9;

/// Of the effect columns at `positions` (in the order chosen), those the earlier ones already
/// span: an effect whose term another chosen effect holds (a spring's constant after an
/// offset). They are held at zero, so the explanation chosen first carries the value: the
/// split between aliased columns is not determined by any data, and would be reported with an
/// unbounded error. A body change's ten columns are not among them: their structural null
/// space stays with the ridge's smallest change, whose physical consistency the ladder tests.
pub(super) fn aliased(h: &DMatrix<f64>, positions: impl IntoIterator<Item = usize>) -> Vec<usize> {
    let mut kept: Vec<usize> = vec![];
    let mut out = vec![];
    for c in positions {
        let own = h[(c, c)];
        let hk = DMatrix::from_fn(kept.len(), kept.len(), |i, j| h[(kept[i], kept[j])]);
        let b = DVector::from_fn(kept.len(), |i, _| h[(kept[i], c)]);
        let explained = match hk.cholesky() {
            Some(ch) => b.dot(&ch.solve(&b)),
            None => 0.0,
        };
        if own > 0.0 && own - explained <= ALIASED * own {
            out.push(c);
        } else if own > 0.0 {
            kept.push(c);
        }
    }
    out
}

/// One fit's normal equations: the data's `w ZᵀZ`, `w Zᵀτ` over `cols`, the prior added with
/// its scale at each solve.
pub(super) struct System<'a> {
    pub(super) cols: Vec<usize>,
    pub(super) h: DMatrix<f64>,
    pub(super) g: DVector<f64>,
    pub(super) prior: &'a DMatrix<f64>,
    pub(super) prior_g: &'a DVector<f64>,
    /// The stated uncertainty's part of the prior (the one the trust region scales).
    pub(super) stated: &'a DMatrix<f64>,
    pub(super) stated_g: &'a DVector<f64>,
    pub(super) theta_d: &'a DVector<f64>,
    /// Columns held at the description's values (friction unless re-identified).
    pub(super) fixed: Vec<usize>,
    /// Indices into `cols` that are free.
    pub(super) free: Vec<usize>,
    /// Positions among the fit's unknowns (`free`, or the reduced ones of `reduce`) of
    /// coefficients with a physical sign (a compliance, a delay, a backlash width, a point
    /// mass, …): held at or above zero, as the selection holds them.
    pub(super) nonneg: Vec<usize>,
    /// `x_free = T y`: the free parameters as a linear map of fewer unknowns, where a point
    /// mass ties a body change's ten parameters to four ([`point_mass_map`]).
    pub(super) reduce: Option<DMatrix<f64>>,
}

/// The map `T` (free × unknowns) of a fit's free parameters onto its unknowns for the point
/// masses whose ten columns start at the `cols` positions given (with their centres), and
/// `nonneg` (positions in `free`) moved to the unknowns, each point mass's mass added; `None`
/// and `nonneg` as given without point masses.
pub(super) fn point_mass_reduction(
    free: &[usize],
    point_masses: &[(usize, [f64; 3])],
    nonneg: Vec<usize>,
) -> (Option<DMatrix<f64>>, Vec<usize>) {
    if point_masses.is_empty() {
        return (None, nonneg);
    }
    let block = |f: usize| {
        point_masses
            .iter()
            .find(|(start, _)| (*start..start + 10).contains(&f))
    };
    let unknowns = free.len() - 6 * point_masses.len();
    let mut t = DMatrix::zeros(free.len(), unknowns);
    let mut moved = vec![];
    let mut k = 0;
    for (i, &f) in free.iter().enumerate() {
        match block(f) {
            Some(&(start, c)) if f == start => {
                let b = point_mass_map(&c);
                for (r, row) in (i..i + 10).enumerate() {
                    for a in 0..4 {
                        t[(row, k + a)] = b[(r, a)];
                    }
                }
                moved.push(k);
                k += 4;
            }
            Some(_) => {}
            None => {
                t[(i, k)] = 1.0;
                if nonneg.contains(&i) {
                    moved.push(k);
                }
                k += 1;
            }
        }
    }
    // `k` only grows: `moved` is in order.
    (Some(t), moved)
}

/// `B(c)` (10 × 4): a body's ten parameters `π = [m, h, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]`
/// (inertia about the body frame's origin) of a point mass near `c` (m, body frame), as a
/// linear map of its mass and first moment `[m, h]`: `I = −m (|c|² 1 − c cᵀ) + Σ_k h_k (2 c_k 1
/// − e_k cᵀ − c e_kᵀ)`, the linearization about `h = m c` of the point mass's `I = (|h|² 1 −
/// h hᵀ)/m`, exact there (`I = m (|c|² 1 − c cᵀ)`) and homogeneous in `(m, h)`.
pub(crate) fn point_mass_map(c: &[f64; 3]) -> nalgebra::SMatrix<f64, 10, 4> {
    let mut b = nalgebra::SMatrix::<f64, 10, 4>::zeros();
    b[(0, 0)] = 1.0;
    for k in 0..3 {
        b[(1 + k, 1 + k)] = 1.0;
    }
    let c2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let delta = |i: usize, j: usize| f64::from(u8::from(i == j));
    // Inertia entries in π order: (x,x) (x,y) (x,z) (y,y) (y,z) (z,z).
    let entries = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    for (r, &(i, j)) in entries.iter().enumerate() {
        b[(4 + r, 0)] = -(c2 * delta(i, j) - c[i] * c[j]);
        for k in 0..3 {
            b[(4 + r, 1 + k)] = 2.0 * c[k] * delta(i, j) - delta(i, k) * c[j] - c[i] * delta(j, k);
        }
    }
    b
}

/// The positions in `free` of the `cols` indices `signed`.
pub(super) fn free_positions(free: &[usize], signed: &[usize]) -> Vec<usize> {
    free.iter()
        .enumerate()
        .filter(|(_, c)| signed.contains(c))
        .map(|(i, _)| i)
        .collect()
}

impl System<'_> {
    /// The free block's scaled system with the stated uncertainty's part of the prior weighted
    /// by `lambda`, and its scales.
    pub(super) fn scaled(&self, lambda: f64) -> (DMatrix<f64>, DVector<f64>, Vec<f64>) {
        let m = self.cols.len();
        let p0 = self.prior.nrows();
        let mut h = self.h.clone();
        let mut g = self.g.clone();
        let mut hv = h.view_mut((0, 0), (p0, p0));
        hv += self.prior + self.stated * (lambda - 1.0);
        let mut gv = g.rows_mut(0, p0);
        gv += self.prior_g + self.stated_g * (lambda - 1.0);
        // A tiny ridge relative to each column's own curvature (a column nothing sees gets a
        // unit one): free effect columns stay determined without being pulled.
        for i in 0..m {
            let v = h[(i, i)];
            h[(i, i)] = if v > 0.0 { v * (1.0 + 1e-10) } else { 1.0 };
        }
        let fixed_value = |f: usize| self.theta_d[f];
        let free = &self.free;
        let hf = DMatrix::from_fn(free.len(), free.len(), |i, j| h[(free[i], free[j])]);
        let gf = DVector::from_fn(free.len(), |i, _| {
            g[free[i]]
                - self
                    .fixed
                    .iter()
                    .map(|&f| h[(free[i], f)] * fixed_value(f))
                    .sum::<f64>()
        });
        let (hf, gf) = match &self.reduce {
            Some(t) => (t.transpose() * hf * t, t.transpose() * gf),
            None => (hf, gf),
        };
        // Scaled to unit diagonal: the prior's precision spans twenty decades (a thin body's
        // J⁻¹), which an unscaled Cholesky turns into garbage.
        let u = hf.nrows();
        let d: Vec<f64> = (0..u).map(|i| 1.0 / hf[(i, i)].sqrt()).collect();
        let hs = DMatrix::from_fn(u, u, |i, j| d[i] * hf[(i, j)] * d[j]);
        let gs = DVector::from_fn(u, |i, _| d[i] * gf[i]);
        (hs, gs, d)
    }

    /// The parameters over `cols` with the stated part of the prior weighted by `lambda`.
    pub(super) fn solve(&self, lambda: f64) -> DVector<f64> {
        let (hs, gs, d) = self.scaled(lambda);
        let y = least_squares_nonneg(&hs, &gs, &self.nonneg);
        let unknowns = DVector::from_fn(y.len(), |i, _| d[i] * y[i]);
        let x = match &self.reduce {
            Some(t) => t * unknowns,
            None => unknowns,
        };
        let mut w = DVector::zeros(self.cols.len());
        for &f in &self.fixed {
            w[f] = self.theta_d[f];
        }
        for (i, &f) in self.free.iter().enumerate() {
            w[f] = x[i];
        }
        w
    }

    /// The fit `w` found at prior weight `lambda`, with its posterior variances.
    pub(super) fn with_variance(self, w: DVector<f64>, lambda: f64) -> Fit {
        let (hs, _, d) = self.scaled(lambda);
        let u = hs.nrows();
        let inv = hs
            .cholesky()
            .map(|c| c.inverse())
            .unwrap_or_else(|| DMatrix::zeros(u, u));
        let cov = DMatrix::from_fn(u, u, |i, j| d[i] * inv[(i, j)] * d[j]);
        let cov = match &self.reduce {
            Some(t) => t * cov * t.transpose(),
            None => cov,
        };
        let mut var = vec![0.0; self.cols.len()];
        for (i, &f) in self.free.iter().enumerate() {
            var[f] = cov[(i, i)];
        }
        let p0 = self.prior.nrows();
        let unseen = (0..self.cols.len())
            .map(|f| f >= p0 && self.h[(f, f)] <= 0.0)
            .collect();
        Fit {
            cols: self.cols,
            w,
            var,
            unseen,
        }
    }
}

impl Problem<'_> {
    /// Held-out sum of squares per block.
    pub(super) fn held_out(&self, data: &Data, fit: &Fit) -> Vec<f64> {
        data.held
            .iter()
            .map(|b| b.select(&fit.cols).residual_sum_of_squares(&fit.w))
            .collect()
    }
}

/// The relative reduction of the summed `after` below `before`, and the block t statistic of
/// the per-block log ratios `ln(before_b / after_b)`: scale-free, so blocks of large torques do
/// not drown a change that helps every block alike.
pub(super) fn improvement(before: &[f64], after: &[f64]) -> (f64, f64) {
    let d: Vec<f64> = before
        .iter()
        .zip(after)
        .map(|(a, b)| (a.max(1e-300) / b.max(1e-300)).ln())
        .collect();
    let k = d.len() as f64;
    let total: f64 = before.iter().sum();
    let mean = d.iter().sum::<f64>() / k;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0).max(1.0);
    let t = if var > 0.0 {
        mean / (var / k).sqrt()
    } else if mean > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    let reduction = (total - after.iter().sum::<f64>()) / total.max(1e-300);
    (reduction, t)
}

/// The description, its prior and the data's weight (the re-identified model's residual).
pub(super) fn problem<'a>(stage: &'a Stage, eps: f64) -> Problem<'a> {
    let (model, train, opts) = (stage.model, stage.train, stage.opts);
    let (_, res) = residual_rms(&stage.ctx_train, train, &[], &stage.theta0, opts.min_speed);
    let masked = mask_slow(train, &res, opts.min_speed);
    let s2 = finite_mean_square(&masked);
    let tau_c = anchor::correlation_time(&masked, model.dof(), train.sample_rate().unwrap_or(1.0));
    let stated = prior_precision(model, eps);
    let prior = match &opts.description_information {
        Some(info) if info.nrows() == model.layout().len => Some(&stated + info),
        _ => None,
    };
    let covered = (0..stated.nrows())
        .filter(|&i| stated[(i, i)] > 0.0)
        .count();
    // With information, the base is held as strongly as the data that determined it: no
    // region is needed (and a real robot's run-to-run differences exceed one run's region).
    let radius2 = match prior {
        Some(_) => f64::INFINITY,
        None => anchor::chi2_upper_quantile(covered, OUTSIDE),
    };
    let prior = prior.unwrap_or_else(|| stated.clone());
    let theta_d = model.parameters();
    Problem {
        stage,
        prior_g: &prior * &theta_d,
        stated_g: &stated * &theta_d,
        theta_d,
        prior,
        stated,
        weight: 1.0 / (s2 * tau_c).max(1e-300),
        radius2,
    }
}

/// Smallest eigenvalue of a body's pseudo-inertia the prior trusts, relative to its trace: an
/// identified description often sits on the boundary `J ⪰ ε_J 1` (a body flat in one
/// direction), where the affine-invariant prior would pin that direction to a relative `ε` of
/// nothing (a precision twenty decades above the others).
pub(super) const J_FLOOR: f64 = 1e-3;

/// [`anchor::prior_precision`] with each body's `J` floored at [`J_FLOOR`] of its trace.
pub(super) fn prior_precision(model: &Model, eps: f64) -> DMatrix<f64> {
    let l = model.layout();
    let mut p = DMatrix::zeros(l.len, l.len);
    let floored = |pi: &InertialParams| {
        let j = pi.pseudo_inertia();
        let floor = J_FLOOR * j.trace();
        InertialParams::from_pseudo_inertia(&(j + nalgebra::Matrix4::identity() * floor))
    };
    let mut put = |c: usize, pi: &InertialParams| {
        p.view_mut((c, c), (10, 10))
            .copy_from(&anchor::body_precision(&floored(pi), eps));
    };
    for (i, b) in model.bodies().iter().enumerate() {
        put(10 * i, &b.inertia);
        if let (Some(c), Some(r)) = (l.rotor_col[i], &b.rotor) {
            put(c, &r.inertia);
        }
    }
    p
}
