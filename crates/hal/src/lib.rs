//! Drivers for the sensor front ends of an IMU board, on embedded-hal 1.0 traits.
//!
//! Filled by the firmware issue; the crate exists now so the workspace has its final shape.
#![no_std]
