//! Dual (biorthogonal) shape functions of a linear slave facet with n = 2 (segment) or
//! n = 3 (triangle) nodes: ψ_i = Σ_l A_il φ_l with ∫_Ω ψ_i φ_j = δ_ij ∫_Ω φ_j on the
//! integration domain Ω (Wohlmuth 2000; Cichosz & Bischoff 2011 for Ω ⊂ facet).

/// Coefficient matrix A of ψ_i = Σ_l A_il φ_l (only the n × n block is used).
pub type Coefficients = [[f64; 3]; 3];

/// A below this value of det(S G S) (G: the Gram matrix on Ω, S = diag(G_ii^(−1/2))) means
/// Ω is too thin for the three linear functions to be told apart: see
/// [`restricted_coefficients`].
pub const GRAM_DET_TOL: f64 = 1e-10;

/// The dual basis on the whole facet, the same in reference coordinates on every facet:
/// segment ψ_1 = 2φ_1 − φ_2, ψ_2 = 2φ_2 − φ_1; triangle ψ_i = 4φ_i − Σ_l φ_l = 4φ_i − 1.
/// From A = D G⁻¹ with G_il = ∫ φ_i φ_l (segment L/6·[[2,1],[1,2]], triangle
/// |T|/12·(I + 11ᵀ)) and D = diag ∫ φ_i (L/2, |T|/3).
pub fn reference_coefficients(n: usize) -> Coefficients {
    let mut a = [[0.0; 3]; 3];
    let (diag, off) = if n == 2 { (2.0, -1.0) } else { (3.0, -1.0) };
    for (i, row) in a.iter_mut().enumerate().take(n) {
        for (l, v) in row.iter_mut().enumerate().take(n) {
            *v = if i == l { diag } else { off };
        }
    }
    a
}

/// The dual basis on a part Ω of the facet: A = diag(m) G⁻¹ with G_il = ∫_Ω φ_i φ_l and
/// m_i = ∫_Ω φ_i, so that ∫_Ω ψ_i φ_j = δ_ij m_j (biorthogonality on Ω: Cichosz &
/// Bischoff, CMAME 200 (2011); Popp et al., CMAME 264 (2013)). On Ω = the whole facet this
/// is [`reference_coefficients`]. None if Ω is (numerically) too thin:
/// det(S G S) < [`GRAM_DET_TOL`].
pub fn restricted_coefficients(
    n: usize,
    gram: &Coefficients,
    m: &[f64; 3],
) -> Option<Coefficients> {
    if (0..n).any(|i| gram[i][i].is_nan() || gram[i][i] <= 0.0) {
        return None;
    }
    let s: Vec<f64> = (0..n).map(|i| 1.0 / gram[i][i].sqrt()).collect();
    let mut g = [[0.0; 3]; 3];
    for i in 0..n {
        for l in 0..n {
            g[i][l] = s[i] * gram[i][l] * s[l];
        }
    }
    let (det, inv) = inverse(n, &g);
    if det.is_nan() || det < GRAM_DET_TOL {
        return None;
    }
    let mut a = [[0.0; 3]; 3];
    for i in 0..n {
        for l in 0..n {
            a[i][l] = m[i] * s[i] * inv[i][l] * s[l];
        }
    }
    Some(a)
}

/// Determinant and inverse (adjugate / det) of the leading n × n block (n = 2 or 3).
fn inverse(n: usize, g: &Coefficients) -> (f64, Coefficients) {
    let mut inv = [[0.0; 3]; 3];
    if n == 2 {
        let det = g[0][0] * g[1][1] - g[0][1] * g[1][0];
        inv[0] = [g[1][1] / det, -g[0][1] / det, 0.0];
        inv[1] = [-g[1][0] / det, g[0][0] / det, 0.0];
        return (det, inv);
    }
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        g[i1][j1] * g[i2][j2] - g[i1][j2] * g[i2][j1]
    };
    let det = g[0][0] * c(0, 0) + g[0][1] * c(0, 1) + g[0][2] * c(0, 2);
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = c(j, i) / det;
        }
    }
    (det, inv)
}

/// ψ_i = Σ_l A_il φ_l for i < n.
pub fn eval(n: usize, a: &Coefficients, phi: &[f64; 3]) -> [f64; 3] {
    let mut psi = [0.0; 3];
    for i in 0..n {
        psi[i] = (0..n).map(|l| a[i][l] * phi[l]).sum();
    }
    psi
}
