//! The checks and the planner on real recipes, and a profile's own G-code
//! checked as its firmware reads it.

mod extruder_turtle;
mod gcode;
mod makers;
mod makers_marlin;
mod package;
mod planner;
