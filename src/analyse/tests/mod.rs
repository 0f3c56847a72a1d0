//! The checks and the planner on real recipes.

mod extruder_turtle;
mod planner;
