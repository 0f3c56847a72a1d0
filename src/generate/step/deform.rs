//! `deform_xyz` and `deform_cylinder` (Kanada's `part.deform_xyz(fd, fc, fv)`).

use glam::DVec3;

use super::{not_finite, vars_with, Polar, PAR_MIN};
use crate::base::error::{Error, Result};
use crate::base::expr::{var, Expr, Lanes, LANES};
use crate::base::par::try_chunks;
use crate::base::toolpath::{frac, Toolpath};

/// A deformation: new positions and/or new cross-sections and speeds.
#[derive(Clone, Debug)]
pub(crate) struct Deform {
    /// In cylinder coordinates (r, theta, z) rather than (x, y, z).
    pub(crate) cylinder: bool,
    /// The three position expressions.
    pub(crate) position: Option<[Expr; 3]>,
    /// New cross-section, per string (sees `c`).
    pub(crate) cross_section: Option<Expr>,
    /// New speed, per string (sees `v`).
    pub(crate) speed: Option<Expr>,
}

impl Deform {
    /// Whether any of `exprs` reads r, and whether any reads theta (atan2,
    /// the costly one, is computed only for expressions that read it).
    fn needs_polar(exprs: &[&Expr]) -> (bool, bool) {
        (
            exprs.iter().any(|e| e.uses(var::R)),
            exprs.iter().any(|e| e.uses(var::THETA)),
        )
    }

    /// Applies the deformation: c and v first, at the old midpoints, then the
    /// points; in chunks (the output is the same for any number of threads).
    pub(crate) fn apply(&self, tp: &mut Toolpath) -> Result<()> {
        if self.cross_section.is_some() || self.speed.is_some() {
            self.apply_strings(tp)?;
        }
        if let Some(pos) = &self.position {
            self.apply_points(tp, pos)?;
        }
        Ok(())
    }

    fn apply_strings(&self, tp: &mut Toolpath) -> Result<()> {
        let exprs: Vec<&Expr> = self.cross_section.iter().chain(&self.speed).collect();
        let (r_too, theta_too) = Self::needs_polar(&exprs);
        let n = tp.len();
        let points = &tp.points;
        let turns = &tp.turns;
        try_chunks(tp.strings.make_mut(), PAR_MIN, |start, chunk| {
            // LANES strings at a time (Expr::eval_many: the same values as
            // eval); travel strings are evaluated too but keep their c and v
            let mut vars = [[0.0; var::COUNT]; LANES];
            let mut lanes = Lanes::new();
            let mut mids = [DVec3::ZERO; LANES];
            let (mut cs, mut vs) = ([0.0; LANES], [0.0; LANES]);
            for (b, block) in chunk.chunks_mut(LANES).enumerate() {
                let first = start + b * LANES;
                let m = block.len();
                for (j, s) in block.iter().enumerate() {
                    let k = first + j;
                    let mid = (points[k] + points[k + 1]) * 0.5;
                    let mut v = vars_with(mid, k, n, r_too, theta_too);
                    v[var::C] = s.c;
                    v[var::V] = s.v;
                    if let Some(u) = turns {
                        v[var::S] = frac(0.5 * (u[k] + u[k + 1]));
                    }
                    vars[j] = v;
                    mids[j] = mid;
                }
                if let Some(e) = &self.cross_section {
                    e.eval_many_in(&vars[..m], &mut cs[..m], &mut lanes);
                }
                if let Some(e) = &self.speed {
                    e.eval_many_in(&vars[..m], &mut vs[..m], &mut lanes);
                }
                for (j, s) in block.iter_mut().enumerate() {
                    if s.travel {
                        continue;
                    }
                    let (k, mid) = (first + j, mids[j]);
                    if let Some(e) = &self.cross_section {
                        let c = cs[j];
                        if !c.is_finite() || c < 0.0 {
                            return Err(bad_value("cross_section", e, c, k, mid, "≥ 0 mm²"));
                        }
                        s.c = c;
                    }
                    if let Some(e) = &self.speed {
                        let v = vs[j];
                        if !v.is_finite() || v <= 0.0 {
                            return Err(bad_value("speed", e, v, k, mid, "> 0 mm/s"));
                        }
                        s.v = v;
                    }
                }
            }
            Ok(())
        })
    }

    fn apply_points(&self, tp: &mut Toolpath, pos: &[Expr; 3]) -> Result<()> {
        let n = tp.points.len();
        let [f0, f1, f2] = pos;
        let cylinder = self.cylinder;
        // theta' = theta needs no trigonometry: (x, y) scales by r'/r.
        let keep_theta = f1.is_var(var::THETA);
        // a cylinder deform needs r (the old radius) but theta only for the
        // expressions it evaluates (f1 is not evaluated when it is theta)
        let evaluated: Vec<&Expr> = if cylinder && keep_theta {
            vec![f0, f2]
        } else {
            vec![f0, f1, f2]
        };
        let (r_used, theta_too) = Self::needs_polar(&evaluated);
        let r_too = cylinder || r_used;
        let turns = &tp.turns;
        try_chunks(&mut tp.points, PAR_MIN, |start, chunk| {
            // LANES points at a time: their variables, then each expression
            // over all of them (Expr::eval_many: the same values as eval)
            let mut vars = [[0.0; var::COUNT]; LANES];
            let mut out = [[0.0; LANES]; 3];
            let mut lanes = Lanes::new();
            // a helix's points repeat their (x, y) every turn: each angle's
            // atan2 once, not once a turn
            let mut polar = theta_too.then(Polar::new);
            for (b, block) in chunk.chunks_mut(LANES).enumerate() {
                let first = start + b * LANES;
                let m = block.len();
                for (j, p) in block.iter().enumerate() {
                    let i = first + j;
                    vars[j] = match &mut polar {
                        Some(memo) => {
                            let mut v = vars_with(*p, i, n, false, false);
                            (v[var::R], v[var::THETA]) = memo.of(*p);
                            v
                        }
                        None => vars_with(*p, i, n, r_too, theta_too),
                    };
                    if let Some(u) = turns {
                        vars[j][var::S] = frac(u[i]);
                    }
                }
                let vars = &vars[..m];
                let [o0, o1, o2] = &mut out;
                f0.eval_many_in(vars, &mut o0[..m], &mut lanes);
                f2.eval_many_in(vars, &mut o2[..m], &mut lanes);
                if !cylinder || !keep_theta {
                    f1.eval_many_in(vars, &mut o1[..m], &mut lanes);
                }
                for (j, point) in block.iter_mut().enumerate() {
                    let p = *point;
                    let q = if !cylinder {
                        DVec3::new(o0[j], o1[j], o2[j])
                    } else {
                        let r = o0[j];
                        let z = o2[j];
                        if keep_theta {
                            let r0 = vars[j][var::R];
                            if r0 > 0.0 {
                                let s = r / r0;
                                DVec3::new(p.x * s, p.y * s, z)
                            } else {
                                DVec3::new(r, 0.0, z)
                            }
                        } else {
                            let th = o1[j];
                            DVec3::new(r * libm::cos(th), r * libm::sin(th), z)
                        }
                    };
                    if !q.is_finite() {
                        let (key, src, value) = worst(pos, &vars[j]);
                        return Err(not_finite(&key, src, value, "point", first + j, p));
                    }
                    *point = q;
                }
            }
            Ok(())
        })
    }
}

/// `position[k]` and the value of the first position expression that is not finite.
fn worst<'a>(pos: &'a [Expr; 3], vars: &crate::base::expr::Vars) -> (String, &'a str, f64) {
    (0..3)
        .map(|k| (k, pos[k].eval(vars)))
        .find(|(_, v)| !v.is_finite())
        .map_or(("position".into(), pos[0].src(), f64::NAN), |(k, v)| {
            (format!("position[{k}]"), pos[k].src(), v)
        })
}

/// The error for a cross-section or speed out of range at string `k`.
fn bad_value(key: &str, e: &Expr, value: f64, k: usize, m: DVec3, expected: &str) -> Error {
    if value.is_finite() {
        Error::input("", format!(
            "{key} `{}` gives {value} at string {k}, midpoint (x, y, z) = ({:.3}, {:.3}, {:.3}); expected {expected}",
            e.src(),
            m.x,
            m.y,
            m.z
        ))
    } else {
        not_finite(key, e.src(), value, "string", k, m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::expr::Params;
    use crate::generate::step::vars_at;

    fn ex(src: &str) -> Expr {
        let all: Vec<usize> = (0..var::COUNT).collect();
        Expr::compile(src, &Params::new(), &all).unwrap()
    }

    fn line() -> Toolpath {
        let mut t = Toolpath::new(DVec3::new(1.0, 0.0, 0.0));
        t.draw(DVec3::new(0.0, 1.0, 1.0), 0.2, 10.0);
        t.draw(DVec3::new(-1.0, 0.0, 2.0), 0.2, 10.0);
        t
    }

    #[test]
    fn cylinder_deform_sees_old_coordinates() {
        let d = Deform {
            cylinder: true,
            position: Some([ex("2*r"), ex("theta"), ex("z + r")]),
            cross_section: Some(ex("c*z")),
            speed: None,
        };
        let mut t = line();
        crate::base::par::on_threads(4, || d.apply(&mut t)).unwrap();
        assert!((t.points[1] - DVec3::new(0.0, 2.0, 2.0)).length() < 1e-12);
        // c evaluated at the old midpoint of string 0 (z = 0.5)
        assert!((t.strings[0].c - 0.1).abs() < 1e-12);
    }

    #[test]
    fn rotation_through_theta() {
        let d = Deform {
            cylinder: true,
            position: Some([ex("r"), ex("theta + pi/2"), ex("z")]),
            cross_section: None,
            speed: None,
        };
        let mut t = line();
        crate::base::par::on_threads(4, || d.apply(&mut t)).unwrap();
        assert!((t.points[0] - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn nan_names_the_place() {
        let d = Deform {
            cylinder: false,
            position: Some([ex("x"), ex("sqrt(y - 0.5)"), ex("z")]),
            cross_section: None,
            speed: None,
        };
        let e = crate::base::par::on_threads(4, || d.apply(&mut line())).unwrap_err();
        assert!(
            e.message.contains("position[1] `sqrt(y - 0.5)`") && e.message.contains("point 0"),
            "{e}"
        );
    }

    fn long_helix(n: usize) -> Toolpath {
        let mut t = Toolpath::new(DVec3::new(10.0, 0.0, 0.0));
        for i in 1..=n {
            let a = i as f64 * 0.05;
            t.draw(
                DVec3::new(10.0 * libm::cos(a), 10.0 * libm::sin(a), i as f64 * 1e-3),
                0.2,
                10.0,
            );
        }
        t
    }

    #[test]
    fn chunks_on_threads_give_the_one_thread_bits_and_the_first_error() {
        // above PAR_MIN, so the points and strings are split among threads
        let n = 120_000;
        let d = Deform {
            cylinder: true,
            position: Some([
                ex("r + sin(5*theta + z)"),
                ex("theta"),
                ex("z + 0.1*cos(x)"),
            ]),
            cross_section: Some(ex("c*(1 + 0.5*sin(i))")),
            speed: None,
        };
        let mut t = long_helix(n);
        let old = t.clone();
        crate::base::par::on_threads(4, || d.apply(&mut t)).unwrap();
        let [f0, _, f2] = d.position.as_ref().unwrap();
        for (i, p) in old.points.iter().enumerate() {
            let vars = vars_at(*p, i, n + 1, true);
            let s = f0.eval(&vars) / vars[var::R];
            let want = DVec3::new(p.x * s, p.y * s, f2.eval(&vars));
            assert_eq!(t.points[i].to_array(), want.to_array(), "point {i}");
        }
        for k in 0..n {
            let mut vars = vars_at(old.midpoint(k), k, n, true);
            vars[var::C] = 0.2;
            vars[var::V] = 10.0;
            let want = d.cross_section.as_ref().unwrap().eval(&vars);
            assert_eq!(t.strings[k].c.to_bits(), want.to_bits(), "string {k}");
        }
        // NaN from point 30001 on, in every chunk: the error names the first
        let bad = Deform {
            cylinder: false,
            position: Some([ex("x"), ex("y"), ex("sqrt(30000.5 - i)")]),
            cross_section: None,
            speed: None,
        };
        let e = crate::base::par::on_threads(4, || bad.apply(&mut long_helix(n))).unwrap_err();
        assert!(e.message.contains("at point 30001,"), "{e}");
    }
}
