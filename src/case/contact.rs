//! `[contact]` / `[[contact]]`: pairs, motions and forces with their histories, friction.

use super::keys;
use super::load;
use super::reader::{Reader, Res, Tab};
use super::shape::vec3;
use super::shape::ObstacleSpec;
use super::tree::{join_index, join_key, Kind, Loc, Node};

/// The forms of `contact.friction`, for messages.
const FRICTION_FORMS: &str = "\"none\", { law = \"tresca\", threshold = ... } or \
                              { law = \"coulomb\", mu = ... }";

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Friction {
    None,
    Tresca {
        threshold: f64,
    },
    /// Coulomb's law node-wise, threshold b_k = μ (−λ_n^k) (docs/friction.md).
    Coulomb {
        mu: f64,
        algorithm: CoulombAlgorithm,
    },
}

/// How Coulomb friction is solved (docs/friction.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoulombAlgorithm {
    /// One generalised semismooth Newton on (C_n, C_τ) with b = μ max(0, −λ_n − c(u_n + g)).
    Newton,
    /// Fixed point on Tresca thresholds b^{m+1} = μ max(0, −λ_n^m), a Tresca solve per step.
    FixedPoint,
}

impl CoulombAlgorithm {
    pub fn name(self) -> &'static str {
        match self {
            CoulombAlgorithm::Newton => "newton",
            CoulombAlgorithm::FixedPoint => "fixed-point",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigidModeHandling {
    Auto,
    None,
}

/// One contact pair: a boundary group against its obstacle (`[contact]`, or one table of
/// `[[contact]]`; docs/obstacles.md, "Several contact pairs").
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSection {
    /// The pair's table in the case file: `contact`, or `contact[i]` of `[[contact]]` (every
    /// message about the pair names its keys under it).
    pub key: String,
    pub group: String,
    pub obstacle: ObstacleSpec,
    /// `contact.motion`: a rigid translation of the obstacle (docs/obstacles.md, "Moving
    /// obstacles"); None: the obstacle stays where it is given.
    pub motion: Option<Motion>,
    /// `contact.force`: force control (docs/obstacles.md, "Force control"): the obstacle moves
    /// along F/|F| by the unknown approach δ until the contact force along F/|F| is |F|
    /// (any friction law; never together with `motion`). Scaled with `[load]` as a motion.
    pub force: Option<Motion>,
    pub friction: Friction,
    pub rigid_modes: RigidModeHandling,
}

/// A rigid translation m of the obstacle, reached at load factor 1: at factor t the obstacle
/// has moved by t·m (by m in every step with `ramp = false`), or, given as a `table` of rows
/// `[t_i, m_i…]`, by the piecewise-linear interpolation of the rows at t (docs/load_steps.md,
/// "Load histories"). The same record holds a prescribed force (`contact.force`), scaled alike.
#[derive(Debug, Clone, PartialEq)]
pub struct Motion {
    /// m, one component per dimension; with a table, the components of its last row.
    pub value: Vec<f64>,
    /// Scaled by the load factor of `[load]` (default); `ramp = false` holds it at m. True
    /// with a table (unused).
    pub ramp: bool,
    /// `KEY.table`: the rows (load factor, components), the factors increasing from 0; empty
    /// for the vector form.
    pub table: Vec<(f64, Vec<f64>)>,
    /// The key of the vector in the case file (`contact.motion`, `contact.motion.value` or
    /// `contact.motion.table`, under `contact[i]` with several pairs).
    pub key: String,
}

impl Motion {
    /// The obstacle's displacement at load factor t: t·m, m when held, or the table's
    /// piecewise-linear interpolation at t (its last row beyond its last factor: the case
    /// reader refuses a run whose factors go beyond it) (padded to 3).
    pub fn at(&self, t: f64) -> [f64; 3] {
        if !self.table.is_empty() {
            return table_at(&self.table, t);
        }
        let m = vec3(&self.value);
        if self.ramp {
            m.map(|x| t * x)
        } else {
            m
        }
    }

    /// The largest load factor the motion is defined at (`None`: every factor).
    pub fn last_factor(&self) -> Option<f64> {
        self.table.last().map(|(t, _)| *t)
    }
}

/// The piecewise-linear interpolation of `rows` (factors increasing) at t, held at the first
/// and the last row outside them.
fn table_at(rows: &[(f64, Vec<f64>)], t: f64) -> [f64; 3] {
    let (first, last) = (&rows[0], &rows[rows.len() - 1]);
    if t <= first.0 {
        return vec3(&first.1);
    }
    if t >= last.0 {
        return vec3(&last.1);
    }
    let i = rows.partition_point(|(ti, _)| *ti <= t).max(1);
    let ((t0, a), (t1, b)) = (&rows[i - 1], &rows[i]);
    let w = (t - t0) / (t1 - t0);
    let (a, b) = (vec3(a), vec3(b));
    std::array::from_fn(|k| a[k] + w * (b[k] - a[k]))
}

impl Reader<'_> {
    /// The contact pairs: one `[contact]` table or an array `[[contact]]`, checked against each
    /// other (distinct groups, one friction law the solver can combine, one rigid-mode
    /// handling).
    pub(super) fn contacts(&self, top: &Tab) -> Res<Vec<ContactSection>> {
        let Some((k, n)) = top.get("contact") else {
            return Ok(Vec::new());
        };
        let pairs = match n.kind {
            Kind::Array(_) => {
                let elems = self.array(
                    &k,
                    n,
                    "a table ([contact]) or an array of tables ([[contact]])",
                )?;
                if elems.is_empty() {
                    return Err(self.err(
                        &k,
                        n.loc,
                        "is empty: give at least one [[contact]] table",
                    ));
                }
                elems
                    .iter()
                    .enumerate()
                    .map(|(i, e)| self.contact(&join_index(&k, i), e))
                    .collect::<Res<Vec<_>>>()?
            }
            _ => vec![self.contact(&k, n)?],
        };
        self.check_pairs(top, &pairs)?;
        Ok(pairs)
    }

    /// What several pairs must agree on (docs/obstacles.md, "Several contact pairs").
    fn check_pairs(&self, top: &Tab, pairs: &[ContactSection]) -> Res<()> {
        let (_, cn) = top.get("contact").expect("pairs were read");
        let elems = match cn.kind {
            Kind::Array(ref a) => a.iter().collect::<Vec<_>>(),
            _ => vec![cn],
        };
        let at = |i: usize, name: &str| -> (String, Loc) {
            let key = join_key(&pairs[i].key, name);
            let loc = match elems[i].kind {
                Kind::Table(ref t) => t
                    .iter()
                    .find(|(n, _)| n.as_str() == name)
                    .map_or(elems[i].loc, |(_, v)| v.loc),
                _ => elems[i].loc,
            };
            (key, loc)
        };
        for (j, b) in pairs.iter().enumerate() {
            if let Some(a) = pairs[..j].iter().find(|a| a.group == b.group) {
                let (key, loc) = at(j, "group");
                return Err(self.err(
                    &key,
                    loc,
                    format!(
                        "\"{}\" is already the group of {}: a contact node belongs to one pair only",
                        b.group, a.key
                    ),
                ));
            }
        }
        // Tresca pairs combine with frictionless ones (threshold 0), Coulomb pairs with
        // frictionless ones (μ = 0) and with each other (each its μ, one algorithm); Tresca and
        // Coulomb are two different iterations and do not mix.
        let coulomb = pairs.iter().find_map(|p| match p.friction {
            Friction::Coulomb { algorithm, .. } => Some((p, algorithm)),
            _ => None,
        });
        if let Some((c, algorithm)) = coulomb {
            let clash = pairs.iter().position(|p| match p.friction {
                Friction::None => false,
                Friction::Tresca { .. } => true,
                Friction::Coulomb { algorithm: a, .. } => a != algorithm,
            });
            if let Some(j) = clash {
                let (key, loc) = at(j, "friction");
                return Err(self.err(
                    &key,
                    loc,
                    format!(
                        "does not combine with {}.friction: Coulomb pairs may have their own μ \
                         but need the same algorithm, and Tresca and Coulomb do not mix \
                         (frictionless pairs combine with either)",
                        c.key
                    ),
                ));
            }
        }
        if let Some(j) = pairs
            .iter()
            .position(|p| p.rigid_modes != pairs[0].rigid_modes)
        {
            let (key, loc) = at(j, "rigid_modes");
            return Err(self.err(
                &key,
                loc,
                format!(
                    "differs from {}.rigid_modes: the body's rigid modes are handled one way",
                    pairs[0].key
                ),
            ));
        }
        Ok(())
    }

    /// One contact pair at `k` (`contact` or `contact[i]`).
    fn contact(&self, k: &str, n: &Node) -> Res<ContactSection> {
        let t = self.table(k, n, keys::CONTACT)?;
        let (gk, g) = self.required(&t, "group")?;
        let group = self.name(&gk, g)?;
        let (ok, o) = self.required(&t, "obstacle")?;
        let obstacle = self.obstacle(&ok, o)?;
        let motion = match t.get("motion") {
            None => None,
            Some((mk, m)) => Some(self.motion(&mk, m, "the obstacle's translation")?),
        };
        let friction = match t.get("friction") {
            None => Friction::None,
            Some((fk, f)) => self.friction(&fk, f)?,
        };
        let force = match t.get("force") {
            None => None,
            Some((fk, f)) => {
                let force = self.motion(&fk, f, "the force pressing the obstacle onto the body")?;
                let why = if motion.is_some() {
                    Some("prescribes the force instead of the motion: give one of them")
                } else if force.table.is_empty() && force.value.iter().all(|&x| x == 0.0) {
                    Some("is zero: force control needs a direction (a nonzero vector)")
                } else {
                    None
                };
                if let Some(why) = why {
                    return Err(self.err(&fk, f.loc, format!("{fk} {why}")));
                }
                Some(force)
            }
        };
        let rigid_modes = match t.get("rigid_modes") {
            None => RigidModeHandling::Auto,
            Some((rk, r)) => self.choice(
                &rk,
                r,
                &[
                    ("auto", RigidModeHandling::Auto),
                    ("none", RigidModeHandling::None),
                ],
            )?,
        };
        Ok(ContactSection {
            key: k.to_string(),
            group,
            obstacle,
            motion,
            force,
            friction,
            rigid_modes,
        })
    }

    /// `contact.motion` (`contact.force`): a vector `[dx, dy(, dz)]`, a table
    /// `{ value = [...], ramp = false }`, or `{ table = [[t, dx, dy(, dz)], ...] }`; `keys`
    /// names the vector and its table entry.
    fn motion(&self, key: &str, n: &Node, what: &str) -> Res<Motion> {
        if let Kind::Table(_) = n.kind {
            let t = self.table(key, n, keys::MOTION)?;
            if let Some((tk, tn)) = t.get("table") {
                if let Some((ok, o)) = t.get("value").or_else(|| t.get("ramp")) {
                    return Err(self.err(
                        &ok,
                        o.loc,
                        format!("{tk} gives the whole history: no '{ok}' beside it"),
                    ));
                }
                let table = self.history_table(&tk, tn, what)?;
                return Ok(Motion {
                    value: table.last().expect("two rows or more").1.clone(),
                    ramp: true,
                    table,
                    key: tk,
                });
            }
            let (vk, v) = self.required(&t, "value")?;
            let value = self.vector(&vk, v)?;
            let ramp = match t.get("ramp") {
                None => true,
                Some((rk, r)) => self.boolean(&rk, r)?,
            };
            return Ok(Motion {
                value,
                ramp,
                table: Vec::new(),
                key: vk,
            });
        }
        let value = match n.kind {
            Kind::Array(_) => self.vector(key, n)?,
            _ => {
                return Err(self.type_err(
                    key,
                    n,
                    &format!(
                        "an array of numbers ({what}), a table {{ value, ramp }} or {{ table }}"
                    ),
                ))
            }
        };
        Ok(Motion {
            value,
            ramp: true,
            table: Vec::new(),
            key: key.to_string(),
        })
    }

    /// `KEY.table`: at least two rows `[load factor, x, y(, z)]`, all of one length (3 in 2D,
    /// 4 in 3D; checked against the mesh later), the first factor 0, the factors increasing.
    fn history_table(&self, key: &str, n: &Node, what: &str) -> Res<Vec<(f64, Vec<f64>)>> {
        let expected = format!("an array of rows [load factor, x, y(, z)] ({what})");
        let rows = self.array(key, n, &expected)?;
        if rows.len() < 2 {
            return Err(self.err(
                key,
                n.loc,
                format!(
                    "needs at least two rows [load factor, x, y(, z)], got {} (a value held in \
                     every step is {{ value = [...], ramp = false }})",
                    rows.len()
                ),
            ));
        }
        if rows.len() > load::MAX_STEPS {
            return Err(self.err(
                key,
                n.loc,
                format!("at most {} rows, got {}", load::MAX_STEPS, rows.len()),
            ));
        }
        let mut out: Vec<(f64, Vec<f64>)> = Vec::with_capacity(rows.len());
        for (i, r) in rows.iter().enumerate() {
            let rk = join_index(key, i);
            let elems = self.array(&rk, r, "a row [load factor, x, y(, z)]")?;
            let width = out.first().map(|(_, v)| v.len() + 1);
            if !(elems.len() == 3 || elems.len() == 4) || width.is_some_and(|w| w != elems.len()) {
                let need = match width {
                    Some(w) => format!("{w} like the first row"),
                    None => "3 (2D) or 4 (3D)".to_string(),
                };
                return Err(self.err(
                    &rk,
                    r.loc,
                    format!(
                        "a row is [load factor, x, y(, z)]: 1 + one number per dimension, \
                         {need}; got {}",
                        elems.len()
                    ),
                ));
            }
            let nums = elems
                .iter()
                .enumerate()
                .map(|(j, e)| self.num(&join_index(&rk, j), e))
                .collect::<Res<Vec<f64>>>()?;
            let t = nums[0];
            match out.last() {
                None if t != 0.0 => {
                    return Err(self.err(
                        &join_index(&rk, 0),
                        r.loc,
                        format!(
                            "the first row's load factor must be 0 (the history starts at the \
                             unloaded state; its values there may be nonzero), got {t}"
                        ),
                    ))
                }
                Some((prev, _)) if t <= *prev => {
                    return Err(self.err(
                        &join_index(&rk, 0),
                        r.loc,
                        format!(
                            "load factor {t} is not above the row before's ({prev}): the \
                             factors of a table must increase"
                        ),
                    ))
                }
                _ => {}
            }
            out.push((t, nums[1..].to_vec()));
        }
        Ok(out)
    }
}

impl Reader<'_> {
    /// `contact.friction`: `"none"` or a table `{ law = ..., ... }`.
    fn friction(&self, key: &str, n: &Node) -> Res<Friction> {
        match &n.kind {
            Kind::Str(s) => self.friction_name(key, n, s),
            Kind::Table(_) => self.friction_table(key, n),
            _ => Err(self.type_err(key, n, FRICTION_FORMS)),
        }
    }

    /// `contact.friction` given as a string: only `"none"` is complete; the names of the laws
    /// get a message on their missing parameter.
    fn friction_name(&self, key: &str, n: &Node, s: &str) -> Res<Friction> {
        match s {
            "none" => Ok(Friction::None),
            "tresca" => Err(self.err(
                key,
                n.loc,
                "Tresca friction needs a threshold: friction = { law = \"tresca\", threshold = ... }",
            )),
            "coulomb" => Err(self.err(
                key,
                n.loc,
                "Coulomb friction needs a friction coefficient: friction = { law = \"coulomb\", mu = ... }",
            )),
            _ => Err(self.err(
                key,
                n.loc,
                format!("unknown value \"{s}\"; allowed: {FRICTION_FORMS}"),
            )),
        }
    }

    /// `contact.friction` given as a table: first its `law`, then the keys that law allows.
    fn friction_table(&self, key: &str, n: &Node) -> Res<Friction> {
        let t = self.table(key, n, keys::FRICTION_ANY)?;
        let (lk, l) = self.required(&t, "law")?;
        #[derive(Clone, Copy)]
        enum Law {
            None,
            Tresca,
            Coulomb,
        }
        let law = self.choice(
            &lk,
            l,
            &[
                ("none", Law::None),
                ("tresca", Law::Tresca),
                ("coulomb", Law::Coulomb),
            ],
        )?;
        match law {
            Law::None => {
                self.table(key, n, keys::FRICTION_NONE)?;
                Ok(Friction::None)
            }
            Law::Tresca => self.tresca(key, n, &t),
            Law::Coulomb => self.coulomb(key, n, &t),
        }
    }

    /// `{ law = "tresca", threshold = ... }` (the table `t` at `key`).
    fn tresca(&self, key: &str, n: &Node, t: &Tab) -> Res<Friction> {
        self.table(key, n, keys::FRICTION_TRESCA)?;
        let (hk, h) = self.required(t, "threshold")?;
        let threshold = self.num(&hk, h)?;
        if threshold < 0.0 {
            return Err(self.err(&hk, h.loc, format!("must be >= 0, got {threshold}")));
        }
        Ok(Friction::Tresca { threshold })
    }

    /// `{ law = "coulomb", mu = ..., algorithm = ... }` (the table `t` at `key`).
    fn coulomb(&self, key: &str, n: &Node, t: &Tab) -> Res<Friction> {
        self.table(key, n, keys::FRICTION_COULOMB)?;
        let (mk, m) = self.required(t, "mu")?;
        let mu = self.num(&mk, m)?;
        if mu < 0.0 {
            return Err(self.err(&mk, m.loc, format!("must be >= 0, got {mu}")));
        }
        let algorithm = match t.get("algorithm") {
            None => CoulombAlgorithm::Newton,
            Some((ak, a)) => self.choice(
                &ak,
                a,
                &[
                    ("newton", CoulombAlgorithm::Newton),
                    ("fixed-point", CoulombAlgorithm::FixedPoint),
                ],
            )?,
        };
        Ok(Friction::Coulomb { mu, algorithm })
    }
}
