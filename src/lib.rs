//! knitfit: fits a knitted stocking onto a 3D leg, after Sakaguchi & Miyata, "A Method of
//! Representing Stockings" (IPSJ), and writes what artists' tools read.
//!
//! Data flows one way: [`scene`] → [`plan`] → [`leg`] / [`knit`] → [`sim`] → [`post`] → [`export`] /
//! [`render`], with [`report`] collecting timings and metrics. [`run`] holds one function per
//! command that strings the stages together. See ARCHITECTURE.md.

pub mod base;
pub mod draw;
pub mod error;
pub mod export;
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

pub use error::{Error, Result};
pub use scene::Scene;
