//! quatarm: the no_std quaternion chain of an articulated-arm CMM.
#![cfg_attr(not(test), no_std)]

pub mod stream;
pub mod encoder;
pub mod angle;
pub mod rotate;
pub mod scalar;
pub mod table;
pub mod chain;
pub mod matrix;
pub mod model;

pub use chain::{Chain, ChainFixed, ChainF32};
pub use matrix::{MatrixChain, MatrixChainF32, MatrixChainFixed};
pub use model::{ChainError, Point};
pub use scalar::{Fixed, Precision, F32};
pub use table::{Table, TableError};
