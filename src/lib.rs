//! quatarm: the no_std quaternion chain of an articulated-arm CMM.
#![cfg_attr(not(test), no_std)]

pub mod stream;
pub mod encoder;
