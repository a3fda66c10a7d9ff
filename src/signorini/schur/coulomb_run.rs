//! The dense Coulomb iteration's record on rank 0: how it ended, its steps, packed for the
//! broadcast.

/// One dense step's record: step, |A_n|, changed, residual, seconds.
pub(super) type DenseStep = (usize, usize, usize, f64, f64);

/// The dense generalised Newton on rank 0 and how it ended.
pub(super) struct DenseCoulomb {
    /// λ of every candidate, d per node in C's order (node frame, normal first).
    pub(super) lambda: Vec<f64>,
    /// The free modes' amplitudes α (u = w + R z α).
    pub(super) alpha: Vec<f64>,
    /// Per candidate: in A_n, slipping.
    pub(super) active: Vec<bool>,
    pub(super) slip: Vec<bool>,
    /// Per step: step, |A_n|, changed, residual, seconds.
    pub(super) steps: Vec<DenseStep>,
    /// `Err`: why the iteration gave up.
    pub(super) end: Result<(), String>,
    /// It stopped by the stall rule (`plain_path::stalled`: the residual at the round-off of the
    /// dense compliance, above COULOMB_RESIDUAL_TOL).
    pub(super) stalled: bool,
    /// The nested start's coarse levels, coarsest first: (nodes, dense steps).
    pub(super) coarse: Vec<(usize, usize)>,
    /// Rank 0, where the last step was in the primal form: its u − G α at the candidates' dofs,
    /// the Schur variables' part of the expansion (else empty: d₀ − C λ). Not broadcast.
    pub(super) x_s: Vec<f64>,
    /// Steps in the primal form (`coulomb_dense::Stiff`).
    pub(super) primal_steps: usize,
    /// The step whose settled slip rows left the system singular, from which the (F5) rows
    /// ran (0: none).
    pub(super) f5_from: usize,
    /// The nested start's coarse levels on which that happened.
    pub(super) f5_coarse: usize,
}

impl DenseCoulomb {
    pub(super) fn failed(n: usize, dim: usize, mz: usize, why: String) -> DenseCoulomb {
        DenseCoulomb {
            lambda: vec![0.0; n * dim],
            alpha: vec![0.0; mz],
            active: vec![false; n],
            slip: vec![false; n],
            steps: Vec::new(),
            end: Err(why),
            stalled: false,
            coarse: Vec::new(),
            x_s: Vec::new(),
            primal_steps: 0,
            f5_from: 0,
            f5_coarse: 0,
        }
    }

    /// All fields as one f64 vector (the broadcast); the reason travels as UTF-8 bytes.
    pub(super) fn pack(&self) -> Vec<f64> {
        let mut v = self.lambda.clone();
        v.extend_from_slice(&self.alpha);
        v.extend(self.active.iter().map(|&a| a as u8 as f64));
        v.extend(self.slip.iter().map(|&a| a as u8 as f64));
        v.push(self.steps.len() as f64);
        for s in &self.steps {
            v.extend([s.0 as f64, s.1 as f64, s.2 as f64, s.3, s.4]);
        }
        let why = self.end.as_ref().err().map_or(&[][..], |w| w.as_bytes());
        v.push(if self.end.is_ok() { 1.0 } else { 0.0 });
        v.push(if self.stalled { 1.0 } else { 0.0 });
        v.push(self.primal_steps as f64);
        v.push(self.f5_from as f64);
        v.push(self.f5_coarse as f64);
        v.push(self.coarse.len() as f64);
        for &(nodes, steps) in &self.coarse {
            v.extend([nodes as f64, steps as f64]);
        }
        v.push(why.len() as f64);
        v.extend(why.iter().map(|&b| b as f64));
        v
    }

    pub(super) fn unpack(v: &[f64], n: usize, dim: usize, mz: usize) -> DenseCoulomb {
        let lambda = v[..n * dim].to_vec();
        let alpha = v[n * dim..n * dim + mz].to_vec();
        let nl = n * dim + mz;
        let active = v[nl..nl + n].iter().map(|&x| x != 0.0).collect();
        let slip = v[nl + n..nl + 2 * n].iter().map(|&x| x != 0.0).collect();
        let mut at = nl + 2 * n;
        let ns = v[at] as usize;
        at += 1;
        let steps = (0..ns)
            .map(|i| {
                let s = &v[at + 5 * i..at + 5 * i + 5];
                (s[0] as usize, s[1] as usize, s[2] as usize, s[3], s[4])
            })
            .collect();
        at += 5 * ns;
        let ok = v[at] != 0.0;
        let stalled = v[at + 1] != 0.0;
        let primal_steps = v[at + 2] as usize;
        let f5_from = v[at + 3] as usize;
        let f5_coarse = v[at + 4] as usize;
        let nc = v[at + 5] as usize;
        let coarse = (0..nc)
            .map(|i| (v[at + 6 + 2 * i] as usize, v[at + 7 + 2 * i] as usize))
            .collect();
        at += 6 + 2 * nc;
        let len = v[at] as usize;
        let bytes: Vec<u8> = v[at + 1..at + 1 + len].iter().map(|&b| b as u8).collect();
        let end = if ok {
            Ok(())
        } else {
            Err(String::from_utf8_lossy(&bytes).into_owned())
        };
        DenseCoulomb {
            lambda,
            alpha,
            active,
            slip,
            steps,
            end,
            stalled,
            coarse,
            x_s: Vec::new(),
            primal_steps,
            f5_from,
            f5_coarse,
        }
    }
}
