//! `material:` resolved: a built-in name, or an inline map checked against
//! what a machine can do.

use crate::base::error::Result;
use crate::machine::{Material, FAN_START_Z};
use crate::recipe::eval::{at, key, Scope};
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
