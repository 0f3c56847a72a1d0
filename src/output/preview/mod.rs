//! Previews: see the print before printing it.
//!
//! Three outputs share one reading of the plan ([`Scene`]): a PNG rendering
//! ([`png`]), a self-contained HTML file with a WebGL viewer ([`html`]) and the
//! PNG thumbnails PrusaSlicer-style printers show from the G-code
//! ([`thumbnail`]). What they show (the views, the colour modes, the
//! [`Options`]) is in `view`, the plan's reading in `scene`, and the choice
//! of format by the file's extension ([`Format`], [`write`], [`bytes`]) in
//! `dispatch`; the index of the passes that gives a string its width is the
//! geometry layer's ([`crate::base::geom::passes`]), shared with the mesh.
//!
//! Projection. Every still view is orthographic. A view is an orthonormal
//! basis (right, up, toward) of recipe space, `toward` pointing at the viewer:
//! a point p lands on the screen plane at (u, w) = (p·right, p·up) and lies at
//! depth d = p·toward (larger is nearer). Pixels are x = cx + s·(u − u_c) and
//! y = cy − s·(w − w_c), with s the scale in px/mm and (u_c, w_c) the centre of
//! the drawing; the minus sign because image rows grow downwards.
//!
//! Width. A string of cross-section c laid h from the next pass (a helix's
//! layer height, measured on the path:
//! [`crate::base::geom::passes::Grid::local_near`]) fills those h along
//! the surface and is c / h thick across it, the real string width. The
//! previews draw it as that flat tube seen from the view: the projection of
//! its cross-section (an ellipse of axes h along the surface and c / h along
//! the normal) onto the screen direction across the string. So a wall seen
//! face on is closed, as printed, and its rim shows the real thickness; a
//! string with no neighbouring pass is drawn round, of diameter 2·sqrt(c/pi).

pub(crate) mod html;
pub(crate) mod png;
pub(crate) mod thumbnail;

mod dispatch;
mod scene;
mod text;
mod view;

pub(crate) use crate::machine::Size;
pub(crate) use dispatch::{Finished, Format, Job, Reader};
pub(crate) use scene::Scene;
pub(crate) use view::{colormap, fmt_value, Basis, ColorMode, Options, View};
