//! Pictures drawn on the GPU (Mesa's lavapipe in CI) checked pixel by pixel.
//! With no adapter at all these tests fail, naming the packages to install.

mod common;
mod pictures;
mod sample;
