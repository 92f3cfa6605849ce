//! The leg's settings (the scene's `leg` and `contact.method`): the file, its units and up axis,
//! which leg to dress, the stocking's axis if given, and how contact queries are answered.
//! Units default to glTF's metres; up defaults to the body's own (found from the anatomy), or
//! glTF's +Y where the body's shape does not show it.

use serde::{Deserialize, Serialize};

use crate::base::settings::Invalid;

/// Length units a leg file can be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Units {
    /// Metres (glTF's unit; default).
    #[default]
    #[serde(rename = "m")]
    Metres,
    /// Decimetres (the MakeHuman base mesh).
    #[serde(rename = "dm")]
    Decimetres,
    /// Centimetres.
    #[serde(rename = "cm")]
    Centimetres,
    /// Millimetres.
    #[serde(rename = "mm")]
    Millimetres,
    /// Inches.
    #[serde(rename = "in")]
    Inches,
}

impl Units {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Decimetres => 0.1,
            Units::Centimetres => 0.01,
            Units::Millimetres => 0.001,
            Units::Inches => 0.0254,
        }
    }

    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Units::Metres => "m",
            Units::Decimetres => "dm",
            Units::Centimetres => "cm",
            Units::Millimetres => "mm",
            Units::Inches => "in",
        }
    }
}

/// Where the file's up axis came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum UpFrom {
    /// Named by `leg.up_axis` (`--up-axis`).
    #[default]
    Given,
    /// `auto`: the file axis nearest the body's up, which its shape makes clear (its ends'
    /// girths differ by [`super::landmarks::CLEAR_ENDS_RATIO`] or more).
    Anatomy,
    /// `auto` where the shape does not make up clear: glTF's +Y.
    Convention,
}

/// Which file axis points up.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum UpAxis {
    /// +Y, glTF's convention (default).
    #[default]
    #[serde(rename = "+y")]
    PosY,
    /// −Y.
    #[serde(rename = "-y")]
    NegY,
    /// +Z (Blender's and many CAD tools' convention).
    #[serde(rename = "+z")]
    PosZ,
    /// −Z.
    #[serde(rename = "-z")]
    NegZ,
    /// +X.
    #[serde(rename = "+x")]
    PosX,
    /// −X.
    #[serde(rename = "-x")]
    NegX,
}

impl UpAxis {
    /// Every axis, in the order a tie between them is broken.
    pub const ALL: [UpAxis; 6] = [
        UpAxis::PosY,
        UpAxis::NegY,
        UpAxis::PosZ,
        UpAxis::NegZ,
        UpAxis::PosX,
        UpAxis::NegX,
    ];

    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            UpAxis::PosY => "+y",
            UpAxis::NegY => "-y",
            UpAxis::PosZ => "+z",
            UpAxis::NegZ => "-z",
            UpAxis::PosX => "+x",
            UpAxis::NegX => "-x",
        }
    }
}

/// How up is found: from the body's shape, or a file axis the user names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(try_from = "String", into = "String")]
pub enum UpChoice {
    /// From the anatomy: the feet are at the bottom (default); glTF's +Y where the shape does
    /// not show which end is up.
    #[default]
    Auto,
    /// This file axis points up.
    Axis(UpAxis),
}

impl UpChoice {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            UpChoice::Auto => "auto",
            UpChoice::Axis(axis) => axis.name(),
        }
    }
}

impl TryFrom<String> for UpChoice {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        if name == "auto" {
            return Ok(UpChoice::Auto);
        }
        UpAxis::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .map(UpChoice::Axis)
            .ok_or_else(|| {
                format!(
                    "unknown up axis \"{name}\": expected \"auto\", \"+y\", \"-y\", \"+z\", \"-z\", \"+x\" or \"-x\""
                )
            })
    }
}

impl From<UpChoice> for String {
    fn from(choice: UpChoice) -> String {
        choice.name().into()
    }
}

/// The character's own side: which leg to dress.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// The character's left leg (default).
    #[default]
    Left,
    /// The character's right leg.
    Right,
}

impl Side {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Side::Left => "left",
            Side::Right => "right",
        }
    }
}

/// Two points on the leg's long axis, in the leg file's coordinates and units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LegAxis {
    /// Bottom of the stocking (near the ankle).
    pub bottom: [f64; 3],
    /// Top of the stocking (upper thigh).
    pub top: [f64; 3],
}

/// The leg to fit onto.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LegSettings {
    /// Leg mesh file, glTF (`.glb` or `.gltf`) or PLY (`.ply`), told apart by extension,
    /// relative to the scene file (default: `"procedural_leg.glb"`, next to the bundled scene).
    pub file: String,
    /// Units of the file's coordinates (default: `"m"`, as glTF specifies).
    pub units: Units,
    /// Which file axis points up, or `"auto"` to find it from the anatomy (default: `"auto"`).
    pub up_axis: UpChoice,
    /// Which leg to dress, the character's own `"left"` or `"right"` (default: `"left"`); a file
    /// with one leg has it dressed whatever its side.
    pub side: Side,
    /// Bottom and top of the stocking on the leg's long axis, in file coordinates; found from
    /// the landmarks and `tube.bottom`/`tube.top` when absent (default: absent).
    pub axis: Option<LegAxis>,
}

impl Default for LegSettings {
    fn default() -> Self {
        LegSettings {
            file: "procedural_leg.glb".into(),
            units: Units::Metres,
            up_axis: UpChoice::Auto,
            side: Side::Left,
            axis: None,
        }
    }
}

/// How yarn/leg contact is found.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactMethod {
    /// Bounding-volume hierarchy (parry) queries (default).
    #[default]
    Bvh,
    /// The paper's test of every point against every triangle: a slow reference.
    Brute,
}

impl ContactMethod {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            ContactMethod::Bvh => "bvh",
            ContactMethod::Brute => "brute",
        }
    }
}

impl LegAxis {
    /// Checks that the points are finite and distinct.
    pub fn validate(&self) -> Result<(), Invalid> {
        let finite = self.bottom.iter().chain(&self.top).all(|c| c.is_finite());
        if !finite {
            return Err(Invalid::new("", "coordinates must be finite numbers"));
        }
        if self.bottom == self.top {
            return Err(Invalid::new("", "bottom and top must be different points"));
        }
        Ok(())
    }
}

impl LegSettings {
    /// Checks every value; the error names the field under `leg`.
    pub fn validate(&self) -> Result<(), Invalid> {
        if self.file.is_empty() {
            return Err(Invalid::new("file", "must name a .glb, .gltf or .ply file"));
        }
        if let Some(axis) = &self.axis {
            axis.validate().map_err(|e| e.within("axis"))?;
        }
        Ok(())
    }
}
