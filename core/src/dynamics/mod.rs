//! Guide dynamics (paper 3): each guide's tip is a damped point mass tied
//! to the tip of its neutral pose, CCD IK bends the guide toward it, a
//! Catmull-Rom curve through the joints is the posed guide; tips are
//! linked to their neighbours, and a guide that enters a collider is
//! rotated out about its root. No step is unstable: the spring is
//! integrated exactly, the IK only rotates, and a root that jumps carries
//! its tip along.
//!
//! One module per step of the paper: [`spring`] (3.1, the tip), [`ik`]
//! (3.1, the joints), [`spline`] (3.1, the output curve), [`links`] (3.2),
//! the push-out of 3.3 is shared geometry ([`crate::collide`]); [`sim`] holds
//! the state and runs the steps.

pub mod ik;
pub mod links;
pub mod params;
pub mod sim;
pub mod spline;
pub mod spring;
pub mod state;
pub mod step;
