//! The scene file: what to knit, with which yarns, how to solve, which effects to simulate and
//! which files to write.
//!
//! JSON, read with serde. Unknown fields are errors (a typo must not be silently ignored); every
//! field has a default, so `{}` is a complete scene. Each stage owns its part (`leg`, `knit`,
//! `sim`, `preview`, `export`, `limits` define the types, their defaults, units and checks); this
//! module only composes them, loads them, and applies command-line flags as [`Override`]s
//! before the one validation, so a flag meets exactly the checks its scene field does and a
//! refusal names the flag that set the value.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::base::settings::{number, Invalid};
use crate::error::{Error, Result};
use crate::export::{default_outputs, Output, YarnsWritten};
use crate::fit::place::toe_on_a_given_axis;
use crate::knit::settings::{KnitSettings, PatchSettings, TubeSettings, Yarns, MAX_NEEDLES};
use crate::knit::{Fabric, Pattern, TubeBottom};
use crate::leg::settings::LegSettings;
use crate::limits::Limits;
use crate::preview::settings::PreviewSettings;
use crate::sim::settings::{ContactSettings, SolverSettings};

/// The scene bundled with the binary (`samples/scene.json`), used when no scene file is given.
pub const BUNDLED_SCENE: &str = include_str!("../samples/scene.json");
/// How the bundled scene is named in messages and reports.
pub const BUNDLED_SCENE_NAME: &str = "samples/scene.json (bundled)";
/// Where the bundled scene's relative paths (its leg) are found: the crate's `samples/`.
pub const BUNDLED_SCENE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/samples");

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// Knit structure: pattern, rest spacing, connection factor.
    pub knit: KnitSettings,
    /// Yarn materials.
    pub yarns: Yarns,
    /// Relaxation solver settings.
    pub solver: SolverSettings,
    /// Physical effects to simulate (default: `["yarn_connection", "alternating_yarns"]`). The
    /// spring force of eq. (1) always runs; everything else runs only when listed here.
    #[serde(default = "default_effects")]
    pub effects: Vec<Effect>,
    /// Files to write besides `report.json`, which is always written
    /// (default: `["ply", "glb", "picture"]`).
    #[serde(default = "default_outputs")]
    pub outputs: Vec<Output>,
    /// The flat-patch experiment (`knitfit patch`).
    pub patch: PatchSettings,
    /// The leg to fit onto (`knitfit fit`).
    pub leg: LegSettings,
    /// The stocking tube (`knitfit fit`).
    pub tube: TubeSettings,
    /// Contact between yarn and leg (`knitfit fit`).
    pub contact: ContactSettings,
    /// The yarn-level preview still (`preview.png` of `knitfit fit`, and `knitfit render`).
    pub render: PreviewSettings,
    /// How much memory a fit may use (`knitfit fit`; see [`crate::limits`]).
    pub limits: Limits,
}

/// A physical effect a scene can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// The connection force of eq. (2): tension drawn along the course yarn.
    YarnConnection,
    /// Nylon and support yarn have their own stiffness. Without it, every spring uses the nylon
    /// yarn's stiffness even where the pattern lays support yarn (an ablation of the paper).
    AlternatingYarns,
    /// Yarn slides on the leg and never enters it (paper §6.2). Always on for a fit.
    Contact,
    /// After a fit, yarn segments that cut through the leg are rerouted over the skin (paper
    /// §6.3). Runs only when a yarn polyline is written (`glb` or `ply`).
    PenetrationFix,
}

impl Effect {
    /// Name as written in scene files and reports.
    pub fn name(self) -> &'static str {
        match self {
            Effect::YarnConnection => "yarn_connection",
            Effect::AlternatingYarns => "alternating_yarns",
            Effect::Contact => "contact",
            Effect::PenetrationFix => "penetration_fix",
        }
    }
}

fn default_effects() -> Vec<Effect> {
    vec![Effect::YarnConnection, Effect::AlternatingYarns]
}

impl Scene {
    /// Reads and validates a scene. `name` is how it is called in messages.
    pub fn from_json(text: &str, name: &str) -> Result<Scene> {
        Ok(LoadedScene::from_json(text, name, None, Vec::new())?.scene)
    }

    /// Reads a scene from a file, or the bundled sample scene when `path` is `None`.
    pub fn load(path: Option<&Path>) -> Result<Scene> {
        Ok(LoadedScene::load(path, Vec::new())?.scene)
    }

    /// The real stocking the scene describes: needles, stitch, yarns.
    pub fn fabric(&self) -> Fabric {
        Fabric::of(&self.knit, &self.yarns, &self.tube)
    }

    /// True when the scene lists `effect`.
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(&effect)
    }

    /// Which yarns `stocking.ply` and `stocking.glb` hold (`outputs` may name `stitches` or
    /// `loops`; the grid's otherwise).
    pub fn yarns_written(&self) -> YarnsWritten {
        if self.wants(Output::Loops) {
            YarnsWritten::Loops
        } else if self.wants(Output::Stitches) {
            YarnsWritten::Stitches
        } else {
            YarnsWritten::Grid
        }
    }

    /// True when the scene asks for `output`.
    pub fn wants(&self, output: Output) -> bool {
        self.outputs.contains(&output)
    }

    /// The check of a scene that `knitfit patch` runs, besides [`Scene::validate`]: a patch's
    /// points are its stitches already, so no `outputs` may ask for its real stitches.
    pub fn check_for_patch(&self) -> std::result::Result<(), Invalid> {
        match self.yarns_written() {
            YarnsWritten::Grid => Ok(()),
            _ => Err(Invalid::new(
                "outputs",
                "\"stitches\" and \"loops\" lay a fit's real stitches on the leg; a patch's \
                 points are its stitches already: leave them out for knitfit patch",
            )),
        }
    }

    /// Checks every value; the error names the field as a dotted path from the scene's top.
    pub fn validate(&self) -> std::result::Result<(), Invalid> {
        self.knit.validate().map_err(|e| e.within("knit"))?;
        self.yarns.validate().map_err(|e| e.within("yarns"))?;
        self.solver.validate().map_err(|e| e.within("solver"))?;
        if self.knit.pattern == Pattern::Plain && self.has(Effect::AlternatingYarns) {
            return Err(Invalid::new(
                "effects",
                "\"alternating_yarns\" needs knit.pattern \"alternating\" (a plain pattern has \
                 one yarn)",
            ));
        }
        self.patch.validate().map_err(|e| e.within("patch"))?;
        self.render.validate().map_err(|e| e.within("render"))?;
        self.tube.validate().map_err(|e| e.within("tube"))?;
        if let Some(circumference) = self.tube.relaxed_circumference_m {
            // The circumference then sets the needles (`Fabric::of`): held to knit.needles'
            // bound, so the real stitch count stays a count.
            let needles = circumference / self.knit.course_spacing_m;
            if needles > MAX_NEEDLES as f64 {
                return Err(Invalid::new(
                    "tube.relaxed_circumference_m",
                    format!(
                        "{} m of {} m stitches is {} needles, over the {MAX_NEEDLES} knit.needles \
                         allows: give a smaller circumference or a larger knit.course_spacing_m",
                        number(circumference),
                        number(self.knit.course_spacing_m),
                        number(needles.round()),
                    ),
                )
                .with(&["knit.course_spacing_m"]));
            }
        }
        if self.tube.relaxed_circumference_m.is_none() && self.tube.wales > self.knit.needles {
            // A grid point stands for one or more real stitches, never for less than one.
            return Err(Invalid::new(
                "knit.needles",
                format!(
                    "{} needles are fewer than the grid's {} wales; a grid point stands for one \
                     real stitch or more: lower tube.wales (--resolution) or raise knit.needles",
                    self.knit.needles, self.tube.wales
                ),
            )
            .with(&["tube.wales"]));
        }
        if self.wants(Output::Stitches) && self.wants(Output::Loops) {
            return Err(Invalid::new(
                "outputs",
                "lists both \"stitches\" and \"loops\"; the yarn files hold one kind of yarn: \
                 name one (or neither, for the simulation grid's yarns)",
            ));
        }
        let yarns = self.yarns_written();
        if yarns != YarnsWritten::Grid && !self.wants(Output::Ply) && !self.wants(Output::Glb) {
            return Err(Invalid::new(
                "outputs",
                format!(
                    "\"{}\" says which yarns stocking.ply and stocking.glb hold, but outputs \
                     lists neither \"ply\" nor \"glb\": add one",
                    if yarns == YarnsWritten::Loops {
                        "loops"
                    } else {
                        "stitches"
                    }
                ),
            ));
        }
        self.contact.validate().map_err(|e| e.within("contact"))?;
        self.leg.validate().map_err(|e| e.within("leg"))?;
        if self.tube.bottom == Some(TubeBottom::Toe) && self.leg.axis.is_some() {
            return Err(toe_on_a_given_axis());
        }
        self.limits.validate().map_err(|e| e.within("limits"))
    }
}

/// The field that names the leg file; a flag that sets it gives a path relative to the current
/// directory, not to the scene file.
pub const LEG_FILE: &str = "leg.file";
/// The field that holds the stocking's axis; a run reports whether a flag set it.
pub const LEG_AXIS: &str = "leg.axis";

/// A command-line flag that sets scene fields (`--tolerance` sets `solver.tolerance`). Applied to
/// the scene before it is validated, so the value meets the same checks as in a scene file; a
/// value the scene refuses is reported under the flag's name.
#[derive(Clone, Debug, PartialEq)]
pub struct Override {
    /// The flag, as typed (`--tolerance`).
    pub flag: String,
    /// The fields it sets, as dotted paths, with their JSON values.
    pub fields: Vec<(String, Value)>,
}

impl Override {
    /// `flag` sets `field` (a dotted path, `solver.tolerance`) to `value`.
    pub fn new(flag: &str, field: &str, value: impl Into<Value>) -> Override {
        Override {
            flag: flag.to_string(),
            fields: vec![(field.to_string(), value.into())],
        }
    }

    /// The same flag also sets `field` to `value`.
    pub fn and(mut self, field: &str, value: impl Into<Value>) -> Override {
        self.fields.push((field.to_string(), value.into()));
        self
    }

    /// True when this flag sets `field`, a field inside it, or a field holding it (so a check
    /// of the whole `tube` is the flag's that set `tube.wales`).
    fn touches(&self, field: &str) -> bool {
        let within = |inner: &str, outer: &str| {
            inner == outer
                || inner
                    .strip_prefix(outer)
                    .is_some_and(|rest| rest.starts_with(['.', '[']))
        };
        self.fields
            .iter()
            .any(|(set, _)| within(field, set) || within(set, field))
    }
}

/// A scene as a run uses it: the validated settings, where they came from, and which flag set
/// which field.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedScene {
    /// The settings.
    pub scene: Scene,
    /// How the scene is named in messages and reports (its path, or the bundled scene's name).
    pub name: String,
    /// The scene file, if one was read: an input no output may replace.
    pub path: Option<PathBuf>,
    /// The flags applied to it, in order.
    pub overrides: Vec<Override>,
}

impl LoadedScene {
    /// Reads the scene file at `path` (the bundled scene when `None`), applies `overrides` and
    /// validates the result once.
    ///
    /// Errors: [`Error::Read`], [`Error::SceneSyntax`] and [`Error::InvalidScene`] naming the
    /// file; [`Error::InvalidArgument`] naming the flag whose value is refused.
    pub fn load(path: Option<&Path>, overrides: Vec<Override>) -> Result<LoadedScene> {
        match path {
            None => LoadedScene::from_json(BUNDLED_SCENE, BUNDLED_SCENE_NAME, None, overrides),
            Some(path) => {
                let text = std::fs::read_to_string(path).map_err(|source| Error::Read {
                    path: path.to_path_buf(),
                    source,
                })?;
                let name = path.display().to_string();
                LoadedScene::from_json(&text, &name, Some(path), overrides)
            }
        }
    }

    /// [`LoadedScene::load`] of a scene's text; `name` is how it is called in messages.
    pub fn from_json(
        text: &str,
        name: &str,
        path: Option<&Path>,
        overrides: Vec<Override>,
    ) -> Result<LoadedScene> {
        let mut scene: Scene = serde_json::from_str(text).map_err(|e| syntax_error(name, &e))?;
        if !overrides.is_empty() {
            scene = apply(scene, &overrides)?;
        }
        let loaded = LoadedScene {
            scene,
            name: name.to_string(),
            path: path.map(Path::to_path_buf),
            overrides,
        };
        loaded.scene.validate().map_err(|e| loaded.refusal(e))?;
        Ok(loaded)
    }

    /// The flag that set `field`, if one did.
    pub fn set_by(&self, field: &str) -> Option<&str> {
        self.overrides
            .iter()
            .rev()
            .find(|o| o.fields.iter().any(|(f, _)| f == field))
            .map(|o| o.flag.as_str())
    }

    /// The directory the scene file's relative paths are resolved against.
    pub fn dir(&self) -> PathBuf {
        match &self.path {
            Some(p) => p.parent().map(Path::to_path_buf).unwrap_or_default(),
            None => PathBuf::from(BUNDLED_SCENE_DIR),
        }
    }

    /// The leg file: `leg.file` relative to the scene file, or as given when a flag set it.
    pub fn leg_path(&self) -> PathBuf {
        match self.set_by(LEG_FILE) {
            Some(_) => PathBuf::from(&self.scene.leg.file),
            None => self.dir().join(&self.scene.leg.file),
        }
    }

    /// `error` as this scene's: a settings value refused by a check that needed the leg
    /// ([`Error::Settings`]) is reported under the scene file or the flag that set it.
    pub fn named(&self, error: Error) -> Error {
        match error {
            Error::Settings(invalid) => self.refusal(invalid),
            other => other,
        }
    }

    /// The files this scene reads (the scene file): none may be replaced by an output.
    pub fn inputs(&self) -> Vec<PathBuf> {
        self.path.iter().cloned().collect()
    }

    /// The error for a value the scene's checks refuse: the last flag's that set one of the
    /// fields it is about, else the scene file's.
    pub fn refusal(&self, invalid: Invalid) -> Error {
        let set_by_flag = |o: &&Override| invalid.fields().any(|f| o.touches(f));
        match self.overrides.iter().rev().find(set_by_flag) {
            Some(o) => Error::InvalidArgument {
                flag: o.flag.clone(),
                message: invalid.message,
            },
            None => Error::InvalidScene {
                path: self.name.clone(),
                field: invalid.field,
                message: invalid.message,
            },
        }
    }
}

/// `scene` with every override's fields set. Each override is first read on its own, so a value
/// of the wrong kind (`--view top`) is refused under its flag with serde's message.
fn apply(scene: Scene, overrides: &[Override]) -> Result<Scene> {
    let as_flag = |o: &Override, e: serde_json::Error| Error::InvalidArgument {
        flag: o.flag.clone(),
        message: e.to_string(),
    };
    for o in overrides {
        let mut alone = Value::Object(Default::default());
        for (field, value) in &o.fields {
            set_field(&mut alone, field, value.clone());
        }
        serde_json::from_value::<Scene>(alone).map_err(|e| as_flag(o, e))?;
    }
    let mut merged = serde_json::to_value(&scene).expect("a scene always serialises");
    for o in overrides {
        for (field, value) in &o.fields {
            set_field(&mut merged, field, value.clone());
        }
    }
    // Each override and the scene read on their own, so together they read too; should a
    // combination not, the last flag is named.
    serde_json::from_value(merged).map_err(|e| as_flag(&overrides[overrides.len() - 1], e))
}

/// Sets the dotted path `field` of a JSON object to `value`, making objects on the way.
fn set_field(root: &mut Value, field: &str, value: Value) {
    let mut node = root;
    let mut parts = field.split('.').peekable();
    while let Some(part) = parts.next() {
        if !node.is_object() {
            *node = Value::Object(Default::default());
        }
        let map = node.as_object_mut().expect("made an object above");
        if parts.peek().is_none() {
            map.insert(part.to_string(), value);
            return;
        }
        node = map
            .entry(part.to_string())
            .or_insert_with(|| Value::Object(Default::default()));
    }
}

/// Turns a serde_json error into a one-line `path:line:column: message` error.
fn syntax_error(name: &str, e: &serde_json::Error) -> Error {
    let full = e.to_string();
    // serde_json appends " at line L column C"; we print the position in front instead.
    let message = match full.rfind(" at line ") {
        Some(at) => full[..at].to_string(),
        None => full,
    };
    Error::SceneSyntax {
        path: name.to_string(),
        line: e.line(),
        column: e.column(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preview::View;

    #[test]
    fn empty_object_is_the_default_scene() {
        let scene = Scene::from_json("{}", "t").unwrap();
        assert_eq!(
            scene,
            Scene {
                effects: default_effects(),
                outputs: default_outputs(),
                ..Scene::default()
            }
        );
    }

    #[test]
    fn bundled_scene_is_valid() {
        Scene::load(None).unwrap();
    }

    #[test]
    fn malformed_json_reports_line_and_column() {
        let err = Scene::from_json(
            "{\n  \"knit\": {\n    \"pattern\": \"plain\",,\n}",
            "s.json",
        )
        .unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("s.json:3:"), "{text}");
        assert!(!text.contains(" at line "), "{text}");
    }

    #[test]
    fn unknown_field_is_named() {
        let err = Scene::from_json("{\"solver\": {\"timestep\": 0.1}}", "s.json").unwrap_err();
        assert!(
            err.to_string().contains("unknown field `timestep`"),
            "{err}"
        );
    }

    #[test]
    fn negative_stiffness_names_the_field() {
        let err = Scene::from_json(
            r#"{"yarns": {"support": {"stiffness": -1, "denier": 5}}}"#,
            "s.json",
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "s.json: yarns.support.stiffness: must be from 1e-6 to 1e6, got -1"
        );
    }

    #[test]
    fn the_real_stocking_is_checked_by_field() {
        let refused = |text: &str| Scene::from_json(text, "s.json").unwrap_err().to_string();
        assert_eq!(
            refused(r#"{"yarns": {"nylon": {"stiffness": 1, "denier": 0}}}"#),
            "s.json: yarns.nylon.denier: must be a positive number, got 0"
        );
        assert_eq!(
            refused(r#"{"yarns": {"support": {"stiffness": 10, "denier": -20}}}"#),
            "s.json: yarns.support.denier: must be a positive number, got -20"
        );
        assert_eq!(
            refused(r#"{"knit": {"needles": 100}}"#),
            "s.json: knit.needles: 100 needles are fewer than the grid's 150 wales; a grid point \
             stands for one real stitch or more: lower tube.wales (--resolution) or raise \
             knit.needles"
        );
        // Values that would put the geometry out of any sane range are refused at the scene,
        // not met as a failed fit.
        assert_eq!(
            refused(r#"{"knit": {"course_spacing_m": 1e308}}"#),
            "s.json: knit.course_spacing_m: must be from 1e-5 to 0.02, got 1e308"
        );
        assert!(refused(r#"{"tube": {"relaxed_circumference_m": 1e9}}"#)
            .starts_with("s.json: tube.relaxed_circumference_m: must be at most 10"));
        assert!(refused(r#"{"knit": {"needles": 1000000}}"#).starts_with("s.json: knit.needles:"));
    }

    #[test]
    fn too_few_needles_for_the_grid_names_the_flag_that_set_it() {
        let err = LoadedScene::from_json(
            "{}",
            "s.json",
            None,
            vec![Override::new("--resolution", "tube.wales", 500)],
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("--resolution: 400 needles are fewer than"),
            "{err}"
        );
    }

    #[test]
    fn plain_pattern_with_alternating_yarns_is_refused() {
        let err = Scene::from_json(
            r#"{"knit": {"pattern": "plain"}, "effects": ["alternating_yarns"]}"#,
            "s.json",
        )
        .unwrap_err();
        assert!(err.to_string().contains("alternating_yarns"), "{err}");
    }

    #[test]
    fn render_settings_are_checked_by_field() {
        let err = Scene::from_json(r#"{"render": {"spp": 0}}"#, "s.json").unwrap_err();
        assert!(
            err.to_string()
                .starts_with("s.json: render.spp: must be 1 to"),
            "{err}"
        );
        let err = Scene::from_json(r#"{"render": {"width": 8192, "height": 8192}}"#, "s.json")
            .unwrap_err();
        assert!(err.to_string().contains("over the limit"), "{err}");
        let err = Scene::from_json(r#"{"render": {"view": "top"}}"#, "s.json").unwrap_err();
        assert!(err.to_string().contains("unknown variant `top`"), "{err}");
        let scene = Scene::from_json(r#"{"render": {"view": "three-quarter"}}"#, "s").unwrap();
        assert_eq!(scene.render.view, View::ThreeQuarter);
    }

    #[test]
    fn zero_patch_size_is_refused() {
        let err = Scene::from_json(r#"{"patch": {"size": [0, 10]}}"#, "s.json").unwrap_err();
        assert!(err.to_string().contains("patch.size"), "{err}");
    }

    fn with(overrides: Vec<Override>) -> Result<LoadedScene> {
        LoadedScene::from_json("{}", "s.json", None, overrides)
    }

    #[test]
    fn a_stocking_to_the_toe_on_a_given_axis_is_refused_by_the_field_or_flag_that_asked() {
        let scene = r#"{"tube": {"bottom": "toe"},
                        "leg": {"axis": {"bottom": [0, 0, 0], "top": [0, 1, 0]}}}"#;
        let err = Scene::from_json(scene, "s.json").unwrap_err().to_string();
        assert!(
            err.starts_with("s.json: tube.bottom: \"toe\" follows"),
            "{err}"
        );
        let bottom = Override::new("--bottom", "tube.bottom", "toe");
        let axis = Override::new(
            "--axis",
            "leg.axis",
            serde_json::json!({"bottom": [0, 0, 0], "top": [0, 1, 0]}),
        );
        let err = with(vec![bottom, axis]).unwrap_err().to_string();
        assert!(err.starts_with("--axis: "), "{err}");
    }

    #[test]
    fn a_flag_sets_its_field_and_a_refused_value_names_the_flag() {
        let loaded = with(vec![Override::new("--tolerance", "solver.tolerance", 1e-4)]).unwrap();
        assert_eq!(loaded.scene.solver.tolerance, 1e-4);
        assert_eq!(loaded.set_by("solver.tolerance"), Some("--tolerance"));
        let err = with(vec![Override::new("--tolerance", "solver.tolerance", 2.0)]).unwrap_err();
        assert_eq!(err.to_string(), "--tolerance: must be in (0, 1), got 2");
    }

    #[test]
    fn a_flag_of_the_wrong_kind_is_refused_by_the_scene_schema() {
        let err = with(vec![Override::new("--contact", "contact.method", "foo")]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "--contact: unknown variant `foo`, expected `bvh` or `brute`"
        );
    }

    #[test]
    fn a_check_of_a_whole_part_is_the_flag_s_that_set_a_field_in_it() {
        let resolution = Override::new("--resolution", "tube.wales", 2).and("tube.courses", 2);
        let err = with(vec![resolution]).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("--resolution: needs at least 3 wales"),
            "{err}"
        );
        let stretch = Override::new(
            "--stretch",
            "patch.stretch",
            serde_json::json!([{"axis": "course", "factor": -1}]),
        );
        let err = with(vec![stretch]).unwrap_err();
        assert_eq!(err.to_string(), "--stretch: must be in (0, 10], got -1");
    }

    #[test]
    fn a_refused_field_no_flag_set_names_the_scene_file() {
        let err = LoadedScene::from_json(
            r#"{"solver": {"damping": -1}}"#,
            "s.json",
            None,
            vec![Override::new("--tolerance", "solver.tolerance", 1e-4)],
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "s.json: solver.damping: must be zero or positive, got -1"
        );
    }

    #[test]
    fn flags_leave_every_other_field_as_the_scene_file_has_it() {
        let text = r#"{"yarns": {"nylon": {"stiffness": 2, "denier": 40}},
                      "tube": {"relaxed_length_m": 0.5}}"#;
        let plain = LoadedScene::from_json(text, "s.json", None, Vec::new()).unwrap();
        let flagged = LoadedScene::from_json(
            text,
            "s.json",
            None,
            vec![Override::new("--leg", "leg.file", "other.glb")],
        )
        .unwrap();
        let mut expected = plain.scene.clone();
        expected.leg.file = "other.glb".into();
        assert_eq!(flagged.scene, expected);
        assert_eq!(flagged.leg_path(), PathBuf::from("other.glb"));
        assert_eq!(
            plain.leg_path(),
            Path::new(BUNDLED_SCENE_DIR).join("procedural_leg.glb")
        );
    }

    #[test]
    fn a_picture_too_large_names_a_size_flag_or_else_the_scene_file() {
        let big = r#"{"render": {"width": 8192, "height": 8192}}"#;
        let view = Override::new("--view", "render.view", "side");
        let err = LoadedScene::from_json(big, "big.json", None, vec![view]).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("big.json: render.width: 8192×8192"),
            "{err}"
        );
        let sizes = vec![
            Override::new("--width", "render.width", 5000),
            Override::new("--height", "render.height", 5000),
            Override::new("--mode", "render.mode", "yarn"),
        ];
        let err = with(sizes).unwrap_err();
        assert!(err.to_string().starts_with("--height: 5000×5000"), "{err}");
    }
}
