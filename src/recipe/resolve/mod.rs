//! Resolution: params evaluated in order (with `--set`), every number
//! evaluated and every expression compiled, images loaded, each error naming
//! its key path.

mod pattern;
mod primitive;
mod solid;
mod turtle;

use std::path::{Path, PathBuf};

use super::eval::Scope;
use super::schema::*;
use super::yaml::parse_yaml;
use crate::base::error::{Error, Result};
use crate::base::expr::var;
use crate::generate::model::{
    Group, Part, Piece, Recipe, Skirt, DEFAULT_CROSS_SECTION, DEFAULT_MAX_STRINGS, DEFAULT_SPEED,
};
use crate::generate::primitive::turtle::Env;
use crate::generate::step::{Bitmap, Deform, Keep, Modulate, ModulateMap, Step};
use crate::machine::{Material, Printer, FAN_START_Z};

/// Evaluates numbers of one recipe: its params, and where images and a
/// turtle's limits come from.
struct Ctx<'a> {
    scope: Scope<'a>,
    dir: &'a Path,
    /// Filament area (mm²) and max_strings, for a turtle (set once known).
    turtle: (f64, u64),
}

impl<'a> std::ops::Deref for Ctx<'a> {
    type Target = Scope<'a>;
    fn deref(&self) -> &Scope<'a> {
        &self.scope
    }
}

const POINT_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::I,
    var::N,
    var::T,
    var::S,
];
const STRING_VARS: &[usize] = &[
    var::X,
    var::Y,
    var::Z,
    var::R,
    var::THETA,
    var::C,
    var::V,
    var::I,
    var::N,
    var::T,
    var::S,
];

impl Recipe {
    /// Reads and resolves a recipe file. `printer` overrides the recipe's printer.
    pub fn load(
        path: &Path,
        sets: &[(String, String)],
        printer: Option<&Printer>,
    ) -> Result<Recipe> {
        let shown = path.display().to_string();
        let text = crate::base::input::read_text(path, "recipe")?;
        let raw: RawRecipe = parse_yaml(&text, &shown)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Recipe::resolve_in(&raw, sets, printer, &dir, Some(path)).map_err(|e| e.in_file(&shown))
    }

    /// Resolves a parsed recipe; relative paths are taken from `dir`.
    pub fn resolve(
        raw: &RawRecipe,
        sets: &[(String, String)],
        printer: Option<&Printer>,
        dir: &Path,
    ) -> Result<Recipe> {
        Recipe::resolve_in(raw, sets, printer, dir, None)
    }

    /// [`Recipe::resolve`] for the recipe read from `file` (so that an
    /// include cycle through it is named).
    fn resolve_in(
        raw: &RawRecipe,
        sets: &[(String, String)],
        printer: Option<&Printer>,
        dir: &Path,
        file: Option<&Path>,
    ) -> Result<Recipe> {
        if raw.p3dp != 1 {
            return Err(Error::input(
                "p3dp",
                format!("format version {} is not known; expected 1", raw.p3dp),
            ));
        }
        if raw.name.trim().is_empty() {
            return Err(Error::input("name", "expected a non-empty name"));
        }
        // names reach G-code comments: one line each, no control characters
        crate::base::safe_text::check("name", &raw.name)?;
        if let Some(d) = &raw.description {
            // a block scalar's final line break is no line of its own
            crate::base::safe_text::check("description", d.trim_end_matches(['\n', '\r']))?;
        }
        if raw.parts.is_empty() {
            return Err(Error::input("parts", "expected at least one part"));
        }
        let library = super::expand::load_library(raw, file, dir)?;
        let params = library.eval_params(sets)?;
        let ctx = Ctx {
            scope: Scope::new(&params),
            dir,
            turtle: (0.0, DEFAULT_MAX_STRINGS),
        };
        let printer = match printer {
            Some(p) => p.clone(),
            None => Printer::resolve(raw.printer.as_deref().unwrap_or("generic-220"), dir)?,
        };
        let material = resolve_material(&ctx, raw.material.as_ref())?;
        let c0 = ctx.positive_or(
            &raw.defaults.cross_section,
            "defaults.cross_section",
            DEFAULT_CROSS_SECTION,
        )?;
        let v0 = ctx.positive_or(&raw.defaults.speed, "defaults.speed", DEFAULT_SPEED)?;
        let skirt = match &raw.skirt {
            Some(s) => Some(Skirt {
                distance: ctx.non_negative(&s.distance, "skirt.distance")?,
                loops: ctx.whole_max(&s.loops, "skirt.loops", 1, 1000)?,
            }),
            None => None,
        };
        let max_strings = match &raw.max_strings {
            Some(n) => ctx.whole(n, "max_strings", 1)? as u64,
            None => DEFAULT_MAX_STRINGS,
        };
        let d = material
            .filament_diameter
            .unwrap_or(printer.filament_diameter);
        let ctx = Ctx {
            turtle: (std::f64::consts::PI * (d / 2.0) * (d / 2.0), max_strings),
            ..ctx
        };
        // templates, loops and groups expanded into leaf parts
        let expansion = super::expand::expand(&raw.parts, &library.templates, &params, dir)?;
        // the limit holds for all parts together too (YAML aliases, loops)
        let total_limit = max_strings;
        let mut total = 0u64;
        let mut parts = Vec::with_capacity(expansion.leaves.len());
        for (k, leaf) in expansion.leaves.iter().enumerate() {
            let place = &leaf.place;
            let ctx = Ctx {
                scope: Scope::new(&leaf.params),
                dir: leaf.dir,
                turtle: ctx.turtle,
            };
            let mut part = resolve_part(&ctx, leaf.part, c0, v0, k).map_err(|e| e.under(place))?;
            if let Some(name) = &leaf.name {
                part.name.clone_from(name);
            }
            part.place.clone_from(place);
            crate::base::safe_text::check(&format!("{place}.name"), &part.name)?;
            let n = part.string_count();
            if n > max_strings {
                return Err(Error::input(
                    format!("{place}.primitive"),
                    format!(
                        "this primitive would make {n} strings, more than the limit of {max_strings}; expected a larger pitch or fewer segments (or raise max_strings)"
                    ),
                ));
            }
            total = total.saturating_add(n);
            if total > total_limit {
                return Err(Error::input(
                    format!("{place}.primitive"),
                    format!(
                        "the parts up to this one make {total} strings, more than the limit of {total_limit} for the whole recipe (all parts together); expected fewer or smaller parts (or raise max_strings)"
                    ),
                ));
            }
            parts.push(part);
        }
        let mut groups = Vec::with_capacity(expansion.groups.len());
        for g in &expansion.groups {
            let ctx = Ctx {
                scope: Scope::new(&g.params),
                dir: g.dir,
                turtle: ctx.turtle,
            };
            let mut steps = Vec::with_capacity(g.steps.len());
            for (j, s) in g.steps.iter().enumerate() {
                steps.push(
                    resolve_step(&ctx, s)
                        .map_err(|e| e.under(&format!("steps[{j}]")).under(&g.place))?,
                );
            }
            groups.push(Group {
                first: g.first,
                end: g.end,
                steps,
                place: g.place.clone(),
            });
        }
        let allow: Vec<String> = raw.allow.iter().map(|a| a.code().to_string()).collect();
        crate::base::finding::validate_allow(&allow, |i| format!("allow[{i}]"))?;
        Ok(Recipe {
            name: raw.name.clone(),
            params,
            printer,
            material,
            skirt,
            parts,
            max_strings,
            allow,
            groups,
        })
    }
}

fn resolve_material(ctx: &Ctx, m: Option<&RawMaterial>) -> Result<Material> {
    match m {
        None => Ok(Material::built_in("pla").unwrap()),
        Some(RawMaterial::Named(n)) => Material::built_in(n).ok_or_else(|| {
            Error::input(
                "material",
                format!("unknown material `{n}`; built-in materials are pla, abs, petg (or give an inline map)"),
            )
        }),
        Some(RawMaterial::Inline(m)) => {
            if let Some(n) = &m.name {
                crate::base::safe_text::check("material.name", n)?;
            }
            let nozzle_temp = ctx.positive(&m.nozzle_temp, "material.nozzle_temp")?;
            let material = Material {
                name: m.name.clone().unwrap_or_else(|| "custom".into()),
                filament_diameter: match &m.filament_diameter {
                    Some(n) => Some(ctx.positive(n, "material.filament_diameter")?),
                    None => None,
                },
                density: ctx.positive(&m.density, "material.density")?,
                nozzle_temp,
                bed_temp: ctx.non_negative(&m.bed_temp, "material.bed_temp")?,
                max_nozzle_temp: ctx.positive_or(&m.max_nozzle_temp, "material.max_nozzle_temp", nozzle_temp + 25.0)?,
                fan_speed: match &m.fan_speed {
                    Some(n) => {
                        let f = ctx.non_negative(n, "material.fan_speed")?;
                        if f > 1.0 {
                            return Err(Error::input(
                                "material.fan_speed",
                                format!("{f} is not allowed; expected a fraction of full speed from 0 to 1"),
                            ));
                        }
                        f
                    }
                    None => 0.0,
                },
                fan_start_z: match &m.fan_start_z {
                    Some(n) => ctx.non_negative(n, "material.fan_start_z")?,
                    None => FAN_START_Z,
                },
                color: match &m.color {
                    Some(c) => crate::machine::material::parse_color(c).ok_or_else(|| {
                        Error::input(
                            "material.color",
                            format!("`{c}` is not a colour; expected `#rrggbb` in hex, e.g. `#FA8F29`"),
                        )
                    })?,
                    None => crate::machine::material::DEFAULT_COLOR,
                },
            };
            material_ranges(&material)?;
            Ok(material)
        }
    }
}

/// Refuses an inline material's values outside what a machine can do (see
/// [`crate::machine::limits`]); the nozzle temperature against the printer's own
/// limit is the `nozzle-temp` check's (a failed check, not unusable input).
fn material_ranges(m: &Material) -> Result<()> {
    use crate::machine::limits::*;
    if let Some(d) = m.filament_diameter {
        range("material.filament_diameter", d, FILAMENT_DIAMETER, "mm")?;
    }
    range("material.density", m.density, DENSITY, "g/cm³")?;
    at_most("material.nozzle_temp", m.nozzle_temp, NOZZLE_TEMP_MAX, "°C")?;
    at_most(
        "material.max_nozzle_temp",
        m.max_nozzle_temp,
        NOZZLE_TEMP_MAX,
        "°C",
    )?;
    at_most("material.bed_temp", m.bed_temp, BED_TEMP_MAX, "°C")?;
    at_most(
        "material.fan_start_z",
        m.fan_start_z,
        MACHINE_LENGTH_MAX,
        "mm",
    )
}

fn resolve_part(ctx: &Ctx, p: &RawPart, c0: f64, v0: f64, k: usize) -> Result<Part> {
    let cross_section = ctx.positive_or(&p.cross_section, "cross_section", c0)?;
    let speed = ctx.positive_or(&p.speed, "speed", v0)?;
    // one primitive or a list, each maybe with its own c and v
    let items = p.primitive.as_ref().map(|p| p.items()).unwrap_or_default();
    if items.is_empty() {
        return Err(Error::input("primitive", "expected at least one primitive"));
    }
    let mut pieces = Vec::with_capacity(items.len());
    for (key, item) in items {
        let c = match &item.cross_section {
            Some(n) => ctx.positive(n, &format!("{key}.cross_section"))?,
            None => cross_section,
        };
        let v = match &item.speed {
            Some(n) => ctx.positive(n, &format!("{key}.speed"))?,
            None => speed,
        };
        // a turtle runs now: its strings start with the part's c and v
        let env = Env {
            cross_section: c,
            speed: v,
            filament_area: ctx.turtle.0,
            max_strings: ctx.turtle.1,
        };
        let primitive = item
            .primitive
            .resolve(&ctx.scope, &env, ctx.dir)
            .map_err(|e| e.under(&key))?;
        // a solid's beads are layer_height × line_width: a cross_section the
        // recipe gives for it would be silently ignored, so refuse it
        if let crate::generate::primitive::Primitive::Solid(sol) = &primitive {
            let bead = sol.layer_height * sol.line_width;
            let given = item.cross_section.is_some() || p.cross_section.is_some();
            if given && (c - bead).abs() > 1e-9 * bead {
                let at = if item.cross_section.is_some() {
                    format!("{key}.cross_section")
                } else {
                    "cross_section".to_string()
                };
                return Err(Error::input(
                    at,
                    format!(
                        "{c} is not used by a solid: its beads are layer_height × line_width = {} mm² (infill squeezed to its spacing); remove cross_section or set it to {}",
                        crate::base::format::fmt_num(bead),
                        crate::base::format::fmt_num(bead)
                    ),
                ));
            }
        }
        pieces.push(Piece {
            primitive,
            cross_section: c,
            speed: v,
        });
    }
    let first = pieces.remove(0);
    let mut steps = Vec::with_capacity(p.steps.len());
    for (j, s) in p.steps.iter().enumerate() {
        steps.push(resolve_step(ctx, s).map_err(|e| e.under(&format!("steps[{j}]")))?);
    }
    Ok(Part {
        name: p.name.clone().unwrap_or_else(|| format!("part {}", k + 1)),
        cross_section: first.cross_section,
        speed: first.speed,
        primitive: first.primitive,
        steps,
        more: pieces,
        place: format!("parts[{k}]"),
        brim: match &p.brim {
            Some(b) => {
                Some(crate::generate::model::Brim {
                    loops: {
                        let n = ctx.positive(&b.loops, "brim.loops")?;
                        if n.fract() != 0.0 || n > 1000.0 {
                            return Err(Error::input(
                            "brim.loops",
                            format!("{n} is not allowed; expected a whole number of loops, 1 to 1000"),
                        ));
                        }
                        n as u32
                    },
                    line_width: ctx.positive_or(&b.line_width, "brim.line_width", 0.45)?,
                    layer_height: ctx.positive_or(&b.layer_height, "brim.layer_height", 0.2)?,
                    speed: ctx.positive_or(&b.speed, "brim.speed", speed)?,
                })
            }
            None => None,
        },
        stand: match &p.stand {
            Some(st) => Some(resolve_stand(ctx, st, speed)?),
            None => None,
        },
    })
}

/// `stand:` resolved; errors name the key under `stand.`.
fn resolve_stand(ctx: &Ctx, st: &RawStand, speed: f64) -> Result<crate::generate::model::Stand> {
    let radius = ctx.positive(&st.radius, "stand.radius")?;
    if radius > 1000.0 {
        return Err(Error::input(
            "stand.radius",
            format!("{radius} mm is not allowed; expected at most 1000 mm"),
        ));
    }
    let walls = match &st.walls {
        Some(n) => {
            let n = ctx.positive(n, "stand.walls")?;
            if n.fract() != 0.0 || n > 100.0 {
                return Err(Error::input(
                    "stand.walls",
                    format!("{n} is not allowed; expected a whole number of walls, 1 to 100"),
                ));
            }
            n as u32
        }
        None => 2,
    };
    Ok(crate::generate::model::Stand {
        radius,
        walls,
        height: match &st.height {
            Some(n) => Some(ctx.positive(n, "stand.height")?),
            None => None,
        },
        line_width: ctx.positive_or(&st.line_width, "stand.line_width", 0.45)?,
        layer_height: ctx.positive_or(&st.layer_height, "stand.layer_height", 0.2)?,
        speed: ctx.positive_or(&st.speed, "stand.speed", speed)?,
    })
}

fn keep(k: &Option<RawKeep>) -> Keep {
    match k {
        Some(RawKeep::Speed) => Keep::Speed,
        _ => Keep::Flow,
    }
}

fn resolve_deform(ctx: &Ctx, d: &RawDeform, key: &str, cylinder: bool) -> Result<Deform> {
    let position = match &d.position {
        Some(p) => Some([
            ctx.expr(&p[0], POINT_VARS, &format!("{key}.position[0]"))?,
            ctx.expr(&p[1], POINT_VARS, &format!("{key}.position[1]"))?,
            ctx.expr(&p[2], POINT_VARS, &format!("{key}.position[2]"))?,
        ]),
        None => None,
    };
    Ok(Deform {
        cylinder,
        position,
        cross_section: match &d.cross_section {
            Some(n) => Some(ctx.expr(n, STRING_VARS, &format!("{key}.cross_section"))?),
            None => None,
        },
        speed: match &d.speed {
            Some(n) => Some(ctx.expr(n, STRING_VARS, &format!("{key}.speed"))?),
            None => None,
        },
    })
}

fn resolve_step(ctx: &Ctx, s: &RawStep) -> Result<Step> {
    Ok(match s {
        RawStep::DeformXyz(d) => Step::DeformXyz(resolve_deform(ctx, d, "deform_xyz", false)?),
        RawStep::DeformCylinder(d) => {
            Step::DeformCylinder(resolve_deform(ctx, d, "deform_cylinder", true)?)
        }
        RawStep::ModulateCylinder { factor, keep: k } => Step::ModulateCylinder(Modulate {
            factor: ctx.expr(factor, STRING_VARS, "modulate_cylinder.factor")?,
            keep: keep(k),
        }),
        RawStep::ModulateMap {
            image,
            text,
            u,
            v,
            dark,
            light,
            threshold,
            keep: k,
        } => {
            let key = "modulate_map";
            let factor = |n: &Option<Num>, name: &str| match n {
                Some(n) => ctx.positive(n, &format!("{key}.{name}")),
                None => Ok(1.0),
            };
            let threshold = match threshold {
                Some(n) => ctx.num(n, &format!("{key}.threshold"))?,
                None => 0.5,
            };
            if !(0.0..=1.0).contains(&threshold) {
                return Err(Error::input(
                    format!("{key}.threshold"),
                    format!("{threshold} is not allowed; expected a number from 0 to 1"),
                ));
            }
            let bitmap = match (image, text) {
                (Some(image), None) => load_bitmap(&ctx.dir.join(image), image)
                    .map_err(|e| e.under(&format!("{key}.image")))?,
                (None, Some(text)) => {
                    Bitmap::from_text(text).map_err(|e| e.under(&format!("{key}.text")))?
                }
                _ => {
                    return Err(Error::input(
                        key,
                        "expected exactly one of `image` (a picture file) and `text` (letters)",
                    ))
                }
            };
            Step::ModulateMap(ModulateMap {
                image: bitmap,
                u: ctx.expr(u, POINT_VARS, &format!("{key}.u"))?,
                v: ctx.expr(v, POINT_VARS, &format!("{key}.v"))?,
                dark: factor(dark, "dark")?,
                light: factor(light, "light")?,
                threshold,
                keep: keep(k),
            })
        }
        RawStep::Subdivide { max_length } => {
            Step::Subdivide(ctx.positive(max_length, "subdivide.max_length")?)
        }
        RawStep::Translate(d) => Step::Translate(ctx.point(d, "translate")?),
    })
}

/// Loads an image as grey levels 0..1; the error names the image as written
/// (an input error with no place: the caller names the key; an I/O failure
/// keeps its [`std::io::ErrorKind`]).
pub fn load_bitmap(path: &PathBuf, shown: &str) -> Result<Bitmap> {
    let io = |message: String, e: &std::io::Error| Error {
        io_kind: Some(e.kind()),
        ..Error::input("", message)
    };
    crate::base::input::note_read(path);
    let open = || {
        image::ImageReader::open(path)
            .map_err(|e| {
                io(
                    format!("cannot open the image `{shown}` ({}): {e}", path.display()),
                    &e,
                )
            })?
            .with_guessed_format()
            .map_err(|e| io(format!("cannot read the image `{shown}`: {e}"), &e))
    };
    // the header's size first: a small file may declare a huge image
    let (w, h) = open()?.into_dimensions().map_err(|e| {
        Error::input(
            "",
            format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}"),
        )
    })?;
    crate::base::input::check_image_size(w, h)
        .map_err(|m| Error::input("", format!("the image `{shown}` {m}")))?;
    let mut reader = open()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(w.max(1));
    limits.max_image_height = Some(h.max(1));
    limits.max_alloc = Some(crate::base::input::MAX_IMAGE_PIXELS * 8);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| {
        Error::input(
            "",
            format!("`{shown}` is not an image p3dp can read (PNG, JPEG, BMP, GIF): {e}"),
        )
    })?;
    let grey = img.to_luma8();
    let (w, h) = grey.dimensions();
    if w == 0 || h == 0 {
        return Err(Error::input("", format!("the image `{shown}` is empty")));
    }
    Ok(Bitmap {
        width: w as usize,
        height: h as usize,
        pixels: grey.as_raw().iter().map(|&p| p as f32 / 255.0).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str) -> Result<Recipe> {
        let raw: RawRecipe = parse_yaml(text, "t.yaml")?;
        Recipe::resolve(&raw, &[], None, Path::new("."))
    }

    const HELIX: &str = "p3dp: 1\nname: h\nparams:\n  radius: 10\n  height: \"2*radius\"\nparts:\n  - primitive: {helix: {radius: radius, height: height, pitch: 0.5}}\n";

    #[test]
    fn params_chain_and_set_overrides() {
        let r = load(HELIX).unwrap();
        assert_eq!(r.params["height"], 20.0);
        let raw: RawRecipe = parse_yaml(HELIX, "t.yaml").unwrap();
        let r = Recipe::resolve(
            &raw,
            &[("radius".into(), "3*4".into())],
            None,
            Path::new("."),
        )
        .unwrap();
        assert_eq!(r.params["height"], 24.0);
        let e = Recipe::resolve(&raw, &[("radios".into(), "3".into())], None, Path::new("."))
            .unwrap_err();
        assert!(e.to_string().contains("unknown param `radios`"), "{e}");
    }

    #[test]
    fn unknown_key_names_the_path_and_line() {
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.5, pich: 1")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("parts[0].primitive.helix.pich"));
        assert_eq!(e.line.map(|l| l.0), Some(7));
        assert!(e.message.contains("expected one of"), "{e}");
    }

    #[test]
    fn bad_values_name_the_key() {
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: -1")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("parts[0].primitive.helix.pitch"));
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.5, segments: 2.5")).unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("parts[0].primitive.helix.segments")
        );
        let e = load(&HELIX.replace("pitch: 0.5", "pitch: 0.0000001")).unwrap_err();
        assert!(e.message.contains("more than the limit"), "{e}");
    }

    #[test]
    fn step_expressions_compile_with_places() {
        let text = format!(
            "{HELIX}    steps:\n      - deform_cylinder: {{position: [r, theta, \"z + \"]}}\n"
        );
        let e = load(&text).unwrap_err();
        assert_eq!(
            e.place.as_deref(),
            Some("parts[0].steps[0].deform_cylinder.position[2]")
        );
        assert!(e.message.contains("z + "), "{e}");
    }

    #[test]
    fn materials() {
        let r = load(&HELIX.replace("name: h", "name: h\nmaterial: petg")).unwrap();
        assert_eq!(r.material.name, "petg");
        let r = load(&HELIX.replace(
            "name: h",
            "name: h\nmaterial: {filament_diameter: 2.85, density: 1.2, nozzle_temp: 200, bed_temp: 50}",
        ))
        .unwrap();
        assert_eq!(r.material.filament_diameter, Some(2.85));
        let e = load(&HELIX.replace("name: h", "name: h\nmaterial: wood")).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("material"));
    }
}
