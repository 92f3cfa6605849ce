//! knitfit: fits a knitted stocking onto a 3D leg, after Sakaguchi & Miyata, "A Method of
//! Representing Stockings" (IPSJ), and writes what artists' tools read.
//!
//! Data flows one way: [`scene`] → [`plan`] → [`leg`] → [`knit`] → [`sim`] → [`post`] →
//! [`export`] / [`draw`] / [`preview`], with [`report`] recording what ran. [`run`] holds one
//! function per command that follows its plan through those stages. The modules are layered:
//! each imports only those below it ([`base`] and [`error`] at the bottom, [`run`] at the
//! top; a test fails on an import cycle). See ARCHITECTURE.md.

pub mod base;
pub mod draw;
pub mod error;
pub mod export;
pub mod fit;
pub mod knit;
pub mod leg;
pub mod limits;
pub mod plan;
pub mod post;
pub mod preview;
pub mod report;
pub mod run;
pub mod scene;
pub mod sim;
pub mod stage;

pub use error::{Error, Result};
pub use scene::Scene;
