//! The funnel rig: a funnel above a tray on a floor, fenced in, and the fill in the funnel's
//! upper part.

use super::ReposeParams;
use crate::config::{FactorySection, RegionSection, ShapeSection, SimulationSection, WallSection};
use crate::lab::experiment::Common;
use crate::lab::observe::Tray;
use crate::lab::scene::{self, UP, on_axis};
use crate::lab::sizes::SizeMix;

/// The rig's heights (above the floor) and radii, m.
pub(super) struct Rig {
    tray_radius: f64,
    /// The tray's top; its side wall reaches down to the floor (tray and stand, one
    /// cylinder).
    z_tray: f64,
    /// The funnel's outlet.
    pub(super) z_out: f64,
    /// The funnel's radius at its outlet and at its inlet.
    r_out: f64,
    r_in: f64,
    /// The funnel's inlet.
    z_top: f64,
    /// The fill region's bottom and radius.
    z_fill: f64,
    r_fill: f64,
    /// Half the domain's width; the fence stands inside it.
    half: f64,
}

impl Rig {
    /// The rig of `p` with a funnel outlet `outlet` m wide, for particles of diameter `d` m,
    /// the tray on a stand `stand` m high.
    pub(super) fn new(p: &ReposeParams, outlet: f64, d: f64, stand: f64) -> Rig {
        let z_tray = stand + p.tray_height;
        let z_out = z_tray + p.drop_height;
        let (r_out, r_in) = (0.5 * outlet, 0.5 * p.funnel_inlet_diameter);
        Rig {
            tray_radius: 0.5 * p.tray_diameter,
            z_tray,
            z_out,
            r_out,
            r_in,
            z_top: z_out + p.funnel_height,
            // Particles appear in the funnel's upper 40 %, inside its wall with one diameter
            // to spare.
            z_fill: z_out + 0.6 * p.funnel_height,
            r_fill: r_out + (r_in - r_out) * 0.6 - d,
            half: r_in.max(0.15) + 0.05,
        }
    }

    /// `[simulation]`: steps of `dt` s up to `max_time`, the skin in diameters of the
    /// smallest grain of `mix` ([`super::SKIN_FRACTION`] unless the experiment sets it).
    pub(super) fn simulation(
        &self,
        c: &Common,
        p: &ReposeParams,
        dt: f64,
        mix: &SizeMix,
    ) -> SimulationSection {
        let skin = c.sim.skin_fraction.unwrap_or(super::SKIN_FRACTION) * mix.min_diameter();
        let domain = scene::domain(self.half, -0.005, self.z_top + 0.05);
        scene::simulation(c, dt, p.max_time, skin, domain)
    }

    /// The funnel, the tray with its side, the fence and the floor.
    pub(super) fn walls(&self, p: &ReposeParams) -> Vec<WallSection> {
        let funnel = ShapeSection::Cone {
            base: on_axis(self.z_out),
            axis: UP,
            radius_base: self.r_out,
            radius_top: self.r_in,
            length: p.funnel_height,
        };
        vec![
            scene::steel("funnel", funnel),
            scene::disc("tray", self.z_tray, self.tray_radius),
            scene::ring("tray_side", 0.0, self.z_tray, self.tray_radius),
            // Keeps what rolls off the tray on the floor, and the rare grain thrown out of
            // the stream (seen with a fine fraction) inside the domain, as high as it goes.
            scene::ring("fence", 0.0, self.z_top + 0.04, self.half - 0.02),
            scene::floor("floor"),
        ]
    }

    /// The factory pouring `count` particles of `mix` (largest diameter `d`, m) into the
    /// funnel at `p.rate`, falling at 0.2 m/s.
    pub(super) fn factory(
        &self,
        p: &ReposeParams,
        count: usize,
        mix: &SizeMix,
        d: f64,
    ) -> FactorySection {
        let region = RegionSection::Cylinder {
            base: on_axis(self.z_fill),
            radius: self.r_fill,
            height: self.z_top - self.z_fill - d,
        };
        scene::soil_factory(region, count, p.rate, [0.0, 0.0, -0.2], mix)
    }

    /// The tray the heap is measured on: particles above the funnel's outlet are not on it.
    pub(super) fn tray(&self) -> Tray {
        Tray {
            centre: on_axis(self.z_tray),
            radius: self.tray_radius,
            ceiling: self.z_out,
        }
    }
}
