//! What every stage's settings share: the error a `validate()` returns (the field, as a dotted
//! path relative to the settings checked, and what is wrong with it) and the common checks.
//!
//! Each stage owns its settings type (`leg::LegSettings`, `sim::SolverSettings`, …) with its
//! defaults and units; the scene only composes them and prefixes the field path
//! ([`Invalid::within`]), so a message names the field as the scene file spells it.

/// A settings value the run cannot use.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Invalid {
    /// The field, as a dotted path (`yarns.support.stiffness`, `patch.stretch[0].factor`).
    pub field: String,
    /// Other fields the check read, whose values share the blame (`width` and `height` for a
    /// picture over its sample budget, named by `spp`).
    pub also: Vec<String>,
    /// What is wrong, and the value found.
    pub message: String,
}

impl Invalid {
    /// `field` cannot be used, because of `message`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Invalid {
        Invalid {
            field: field.into(),
            also: Vec::new(),
            message: message.into(),
        }
    }

    /// The same error, caused by `fields` as well.
    pub fn with(mut self, fields: &[&str]) -> Invalid {
        self.also.extend(fields.iter().map(|f| f.to_string()));
        self
    }

    /// Every field the error is about, `field` first.
    pub fn fields(&self) -> impl Iterator<Item = &str> {
        std::iter::once(self.field.as_str()).chain(self.also.iter().map(String::as_str))
    }

    /// The same error seen from settings that hold these under `prefix` (`"knit"`).
    pub fn within(self, prefix: &str) -> Invalid {
        let prefixed = |field: &str| {
            if field.is_empty() {
                prefix.to_string()
            } else if field.starts_with('[') {
                format!("{prefix}{field}")
            } else {
                format!("{prefix}.{field}")
            }
        };
        Invalid {
            field: prefixed(&self.field),
            also: self.also.iter().map(|f| prefixed(f)).collect(),
            message: self.message,
        }
    }
}

/// Checks that `value` is a finite number above zero.
pub fn positive(field: &str, value: f64) -> Result<(), Invalid> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            field,
            format!("must be a positive number, got {value}"),
        ))
    }
}

/// Checks that `value` is a finite number above zero and at most `max`.
pub fn positive_at_most(field: &str, value: f64, max: f64) -> Result<(), Invalid> {
    positive(field, value)?;
    if value <= max {
        Ok(())
    } else {
        Err(Invalid::new(
            field,
            format!("must be at most {max}, got {}", number(value)),
        ))
    }
}

/// Checks that `value` is a finite number from `min` to `max`, both included: a bound that keeps
/// a physical setting within what any stocking has, so an absurd one is refused at the load
/// rather than diverging the solver later.
pub fn within(field: &str, value: f64, min: f64, max: f64) -> Result<(), Invalid> {
    if value.is_finite() && (min..=max).contains(&value) {
        Ok(())
    } else {
        Err(Invalid::new(
            field,
            format!(
                "must be from {} to {}, got {}",
                number(min),
                number(max),
                number(value)
            ),
        ))
    }
}

/// A number as a person would write it: `0.5`, but `1e308` rather than 309 digits.
pub fn number(value: f64) -> String {
    if value != 0.0 && !(1e-4..1e6).contains(&value.abs()) {
        format!("{value:e}")
    } else {
        format!("{value}")
    }
}

/// Checks that `value` is a finite number, zero or above.
pub fn non_negative(field: &str, value: f64) -> Result<(), Invalid> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(Invalid::new(
            field,
            format!("must be zero or positive, got {value}"),
        ))
    }
}

/// Checks that every channel of a colour is in [0, 1].
pub fn colour(field: &str, value: [f64; 3]) -> Result<(), Invalid> {
    if value
        .iter()
        .all(|c| c.is_finite() && (0.0..=1.0).contains(c))
    {
        Ok(())
    } else {
        Err(Invalid::new(
            field,
            format!("each channel must be in [0, 1], got {value:?}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_is_named_from_the_scene_down() {
        let e = Invalid::new("stiffness", "bad")
            .within("support")
            .within("yarns");
        assert_eq!(e.field, "yarns.support.stiffness");
        let e = Invalid::new("[2].factor", "bad").within("stretch");
        assert_eq!(e.field, "stretch[2].factor");
        assert_eq!(Invalid::new("", "bad").within("tube").field, "tube");
        let e = Invalid::new("spp", "bad").with(&["width"]).within("render");
        assert_eq!(
            e.fields().collect::<Vec<_>>(),
            ["render.spp", "render.width"]
        );
    }
}
