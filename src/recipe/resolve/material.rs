//! `material:` resolved: a built-in name, or an inline map checked against
//! what a machine can do; or a slicer's filament preset (`--filament`),
//! which replaces the recipe's material.

use crate::base::error::{Error, Result};
use crate::base::input::Reads;
use crate::machine::material::FilamentPreset;
use crate::machine::{Material, FAN_START_Z};
use crate::recipe::eval::{at, key, Scope};
use crate::recipe::preset::{self, Format, Preset, Source};
use crate::recipe::schema::{InlineMaterial, RawMaterial};

/// The material; `s` is under `material`. PLA when none is given.
pub(super) fn resolve(s: &Scope, m: Option<&RawMaterial>) -> Result<Material> {
    match m {
        None => Ok(Material::built_in("pla").unwrap()),
        Some(RawMaterial::Named(n)) => Material::built_in(n).ok_or_else(|| {
            s.error(
                "",
                format!("unknown material `{n}`; built-in materials are pla, abs, petg (or give an inline map)"),
            )
        }),
        Some(RawMaterial::Inline(m)) => {
            let material = inline(s, m)?;
            ranges(s, m, &material)?;
            Ok(material)
        }
    }
}

/// An inline material's values, each evaluated.
fn inline(s: &Scope, m: &InlineMaterial) -> Result<Material> {
    if let Some(n) = &m.name {
        crate::base::safe_text::check(&s.place(key!(m.name)), n)?;
    }
    let nozzle_temp = s.positive(at!(m.nozzle_temp))?;
    Ok(Material {
        name: m.name.clone().unwrap_or_else(|| "custom".into()),
        filament_diameter: at!(m.filament_diameter)
            .some()
            .map(|n| s.positive(n))
            .transpose()?,
        density: s.positive(at!(m.density))?,
        nozzle_temp,
        bed_temp: s.non_negative(at!(m.bed_temp))?,
        max_nozzle_temp: s.positive_or(at!(m.max_nozzle_temp), nozzle_temp + 25.0)?,
        fan_speed: match at!(m.fan_speed).some() {
            Some(n) => {
                let f = s.non_negative(n)?;
                if f > 1.0 {
                    return Err(s.error(
                        n.key,
                        format!(
                            "{f} is not allowed; expected a fraction of full speed from 0 to 1"
                        ),
                    ));
                }
                f
            }
            None => 0.0,
        },
        fan_start_z: match at!(m.fan_start_z).some() {
            Some(n) => s.non_negative(n)?,
            None => FAN_START_Z,
        },
        color: match &m.color {
            Some(c) => crate::machine::material::parse_color(c).ok_or_else(|| {
                s.error(
                    key!(m.color),
                    format!("`{c}` is not a colour; expected `#rrggbb` in hex, e.g. `#FA8F29`"),
                )
            })?,
            None => crate::machine::material::DEFAULT_COLOR,
        },
        // a recipe's own material prints at its nozzle_temp: the coolest it
        // is known to take
        min_nozzle_temp: nozzle_temp,
        max_volumetric_speed: None,
        chamber_temp: 0.0,
        vitrification_temp: None,
        preset: None,
    })
}

/// Refuses an inline material's values outside what a machine can do (see
/// [`crate::machine::limits`]); the nozzle temperature against the printer's own
/// limit is the `nozzle-temp` check's (a failed check, not unusable input).
fn ranges(s: &Scope, raw: &InlineMaterial, m: &Material) -> Result<()> {
    use crate::machine::limits::*;
    let at = |key: &str| s.place(key);
    if let Some(d) = m.filament_diameter {
        range(&at(key!(raw.filament_diameter)), d, FILAMENT_DIAMETER, "mm")?;
    }
    range(&at(key!(raw.density)), m.density, DENSITY, "g/cm³")?;
    at_most(
        &at(key!(raw.nozzle_temp)),
        m.nozzle_temp,
        NOZZLE_TEMP_MAX,
        "°C",
    )?;
    at_most(
        &at(key!(raw.max_nozzle_temp)),
        m.max_nozzle_temp,
        NOZZLE_TEMP_MAX,
        "°C",
    )?;
    at_most(&at(key!(raw.bed_temp)), m.bed_temp, BED_TEMP_MAX, "°C")?;
    at_most(
        &at(key!(raw.fan_start_z)),
        m.fan_start_z,
        MACHINE_LENGTH_MAX,
        "mm",
    )
}

/// The material of the filament preset `src` names (`--filament FILE
/// [--filament-preset NAME]`): its temperatures, filament diameter,
/// density, flow limit, temperature range and colour, and every setting for
/// the start and end G-code; each value held to what a machine can do, an
/// error naming the preset file and key.
pub(crate) fn from_filament(src: &Source, reads: &Reads) -> Result<Material> {
    let p = preset::load_filament(src, reads)?;
    from_preset(&p)
}

/// [`from_filament`] of a loaded preset.
pub(crate) fn from_preset(p: &Preset) -> Result<Material> {
    let at = |key: &str, message: String| {
        Error::input(key, format!("filament preset `{}`: {message}", p.name)).in_file(&p.file)
    };
    let need = |keys: &[&str], what: &str| -> Result<f64> {
        match p.first_number(keys)? {
            Some(v) if v > 0.0 => Ok(v),
            _ => Err(at(
                keys[0],
                format!(
                    "no {what} (`{}`); p3dp needs it to print",
                    keys.join("` or `")
                ),
            )),
        }
    };
    let positive =
        |keys: &[&str]| -> Result<Option<f64>> { Ok(p.first_number(keys)?.filter(|v| *v > 0.0)) };
    crate::base::safe_text::check("filament preset", &p.name)?;
    let nozzle_temp = need(&["temperature", "nozzle_temperature"], "nozzle temperature")?;
    // p3dp's one bed temperature: PrusaSlicer's, else the plate OrcaSlicer
    // and Bambu Studio heat for p3dp's default plate (textured PEI)
    let bed_temp = need(
        &[
            "bed_temperature",
            "textured_plate_temp",
            "hot_plate_temp",
            "eng_plate_temp",
            "cool_plate_temp",
        ],
        "bed temperature",
    )?;
    let density = need(&["filament_density"], "density (g/cm³)")?;
    let fan = p
        .first_number(&["min_fan_speed", "fan_min_speed"])?
        .unwrap_or(0.0);
    let m = Material {
        name: crate::base::safe_text::one_line(&p.name).into_owned(),
        filament_diameter: positive(&["filament_diameter"])?,
        density,
        nozzle_temp,
        bed_temp,
        max_nozzle_temp: positive(&["nozzle_temperature_range_high"])?
            .unwrap_or(nozzle_temp + 25.0),
        fan_speed: (fan / 100.0).clamp(0.0, 1.0),
        fan_start_z: FAN_START_Z,
        color: p
            .text("filament_colour")
            .and_then(|c| crate::machine::material::parse_color(c.trim()))
            .unwrap_or(crate::machine::material::DEFAULT_COLOR),
        min_nozzle_temp: positive(&["nozzle_temperature_range_low"])?.unwrap_or(nozzle_temp),
        max_volumetric_speed: positive(&["filament_max_volumetric_speed"])?,
        chamber_temp: p
            .first_number(&["chamber_temperature", "chamber_temperatures"])?
            .unwrap_or(0.0)
            .max(0.0),
        vitrification_temp: positive(&["temperature_vitrification"])?,
        preset: Some(FilamentPreset {
            name: p.name.clone(),
            file: p.file.clone(),
            settings: p
                .values
                .keys()
                .filter_map(|k| {
                    let v = preset::map::typed(p, k, 1)?;
                    Some((k.clone(), crate::recipe::profile::variable(v)))
                })
                .collect(),
        }),
    };
    preset_ranges(p, &m)?;
    Ok(m)
}

/// A filament preset's values held to what a machine can do (as an inline
/// material's are), an error naming the preset's key.
fn preset_ranges(p: &Preset, m: &Material) -> Result<()> {
    use crate::machine::limits::*;
    let in_file = |e: Error| {
        Error {
            message: format!("filament preset `{}`: {}", p.name, e.message),
            ..e
        }
        .in_file(&p.file)
    };
    let nozzle = if p.format == Format::Ini {
        "temperature"
    } else {
        "nozzle_temperature"
    };
    if let Some(d) = m.filament_diameter {
        range("filament_diameter", d, FILAMENT_DIAMETER, "mm").map_err(in_file)?;
    }
    range("filament_density", m.density, DENSITY, "g/cm³").map_err(in_file)?;
    at_most(nozzle, m.nozzle_temp, NOZZLE_TEMP_MAX, "°C").map_err(in_file)?;
    at_most(
        "nozzle_temperature_range_high",
        m.max_nozzle_temp,
        NOZZLE_TEMP_MAX,
        "°C",
    )
    .map_err(in_file)?;
    at_most("bed_temperature", m.bed_temp, BED_TEMP_MAX, "°C").map_err(in_file)?;
    at_most("chamber_temperature", m.chamber_temp, BED_TEMP_MAX, "°C").map_err(in_file)?;
    if let Some(q) = m.max_volumetric_speed {
        at_most("filament_max_volumetric_speed", q, FLOW_MAX, "mm³/s").map_err(in_file)?;
    }
    Ok(())
}
