//! quatarm: the no_std quaternion chain of an articulated-arm CMM.
#![cfg_attr(not(test), no_std)]

pub mod angle;
pub mod chain;
pub mod encoder;
pub mod matrix;
pub mod model;
pub mod physics;
pub mod rotate;
pub mod scalar;
pub mod stream;
pub mod table;
pub mod temperature;

pub use chain::{Chain, ChainF32, ChainFixed, Evaluator};
pub use matrix::{MatrixChain, MatrixChainF32, MatrixChainFixed};
pub use model::{ChainError, Point};
pub use physics::Physics;
pub use scalar::{Arithmetic, Fixed, F32};
pub use table::{Table, TableError};
