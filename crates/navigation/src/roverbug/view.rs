//! The view and gaze control (paper 000 section 2): at every sensing position the C-obstacles
//! are rebuilt from the wedges sensed there (no global map), and the navigator chooses which
//! wedges to sense: the mast toward the goal, along the boundary in normal boundary following,
//! the mast scan of virtual boundary following, and the forward body pair.
//!
//! Departures kept here:
//! * the C-obstacles of the last view within reach of the rover are carried to the next one
//!   (the mast is blind within a metre, `near_visible_m`), unless they lie outside that blind
//!   zone and the new view has sensed their ground again: the nearer view supersedes them
//!   (stale copies, seen from farther, pile up and close the gaps of a rock field). The paper
//!   passes "explicitly recorded points and parameters" between steps; these are such records;
//! * recorded hazard contacts, dead ends and mission keep-out zones are C-obstacles like sensed
//!   ones, and the safety layer's own C-obstacles join them (see `safety`);
//! * gaze control also looks at the ground a drive was held back from (see `unseen`);
//! * while a squeeze lasts (see `recovery::squeeze`) the sensed C-obstacles are grown without
//!   the safety buffer.

use super::{
    CObstacle, Mode, NavCommand, NavInput, Outcome, Point2, Pose2, RoverBug, SenseRequest, SensedWedge,
    TerrainConfig, TerrainEvaluator, View, angle_diff, safety_terrain,
};

impl RoverBug {
    /// Half-angle of a mast wedge (rad).
    pub(super) fn alpha_mast(&self) -> f64 {
        0.5 * self.rover.mast_fov
    }

    /// Far radius of a mast wedge (m).
    pub(super) fn range(&self) -> f64 {
        self.rover.mast_range
    }

    /// Requests range images, counting every wedge (gaze control).
    pub(super) fn sense(&mut self, requests: Vec<SenseRequest>) -> NavCommand {
        if self.stats.sensing_actions >= self.config.budgets.max_wedges {
            let why = format!("no arrival after {} wedges sensed", self.stats.sensing_actions);
            return self.finish_now(Outcome::HelpRequested, &why);
        }
        self.stats.sensing_actions += requests.len() as u64;
        NavCommand::Sense(requests)
    }

    /// The mast wedge (the navigation image) centred on the
    /// world bearing `bearing`.
    pub(super) fn mast_at(&self, pose: Pose2, bearing: f64) -> SenseRequest {
        let pan = angle_diff(bearing, pose.yaw);
        SenseRequest::Mast { pan }
    }

    /// The sensing that opens a step in the current mode.
    pub(super) fn open_step(&mut self, pose: Pose2, goal: Point2) -> NavCommand {
        self.view = None;
        self.reversing = false;
        self.new_view(pose);
        if let Some((outcome, why)) = self.finish.clone() {
            return NavCommand::Finish(outcome, why);
        }
        if self.steps > self.config.budgets.max_steps {
            let why = format!("no arrival in {} steps", self.config.budgets.max_steps);
            return self.finish_now(Outcome::HelpRequested, &why);
        }
        let toward_goal = goal.sub(pose.position()).angle();
        let mut requests = vec![self.mast_at(pose, toward_goal)];
        if let Mode::Normal { sense, .. } = self.mode {
            // Also along the boundary, a quarter turn from the goal direction.
            requests.push(self.mast_at(pose, pose.yaw + sense * self.alpha_mast()));
        }
        if let Some(target) = self.look_at.take()
            && target.dist(pose.position()) > self.config.paper.near_visible
        {
            // Gaze control: the ground a drive was held back from, beyond the mast's blind
            // zone, unless the wedge toward the goal covers it.
            let bearing = target.sub(pose.position()).angle();
            if angle_diff(bearing, toward_goal).abs() > 0.5 * self.alpha_mast() {
                requests.push(self.mast_at(pose, bearing));
            }
        }
        requests.push(SenseRequest::BodyFront);
        if let Mode::Virtual { .. } = self.mode {
            self.mode = Mode::MotionToGoal;
        }
        self.sense(requests)
    }

    /// Starts a new sense-plan-act step at the current position. The C-obstacles of the last
    /// view that lie within reach of the rover are recorded and carried over: the mast cannot
    /// see the ground within a metre of the rover.
    pub(super) fn new_view(&mut self, pose: Pose2) {
        let x = pose.position();
        let reach = self.config.paper.near_visible + 0.5;
        self.carried = std::mem::take(&mut self.obstacles);
        self.carried.truncate(self.sensed_len);
        self.carried.retain(|o| o.signed_clearance(x) < reach);
        if self.safety.is_none() {
            let config = safety_terrain(&self.rover, &self.config);
            self.safety = TerrainEvaluator::new(config, pose).ok();
        }
        self.view = match TerrainEvaluator::new(self.terrain.clone(), pose) {
            Ok(evaluator) => Some(View { evaluator, wedges: Vec::new(), origin: pose.position() }),
            Err(e) => {
                self.finish = Some((Outcome::Aborted, format!("terrain configuration of the rover: {e}")));
                None
            }
        };
        self.steps += 1;
    }

    /// Folds the clouds of the last frame into the current view and rebuilds the C-obstacles.
    pub(super) fn ingest(&mut self, input: &NavInput<'_>) {
        let pose = input.estimate.pose.pose2();
        if self.view.is_none() {
            self.new_view(pose);
        }
        let Some(view) = self.view.as_mut() else { return };
        for cloud in &input.frame.clouds {
            view.wedges.push(SensedWedge { pose, wedge: cloud.wedge });
            self.drawn_wedges.push(wedge_polygon(pose, &cloud.wedge));
        }
        view.evaluator.update(&input.frame.clouds, &input.estimate);
        if let Some(safety) = self.safety.as_mut() {
            safety.update(&input.frame.clouds, &input.estimate);
        }
        self.supersede_carried();
        self.safety_hazard = self.confirm_hazards();
        self.rebuild_obstacles(pose, input.goal, true);
    }

    /// The terrain settings the C-obstacles are grown with: without the safety buffer while
    /// squeezing.
    pub(super) fn growth_terrain(&self) -> TerrainConfig {
        let squeezing = self
            .squeezed
            .is_some_and(|(at, way_on)| way_on && self.steps < at + self.config.recovery.squeeze_views);
        if squeezing {
            TerrainConfig { safety_buffer: 0.0, ..self.terrain.clone() }
        } else {
            self.terrain.clone()
        }
    }

    /// Builds the C-obstacles of the current view (with the carried ones, the safety layer's,
    /// recorded contacts and dead ends, and keep-out zones), recording the sensed and safety
    /// layer ones for the picture when `draw`.
    pub(super) fn rebuild_obstacles(&mut self, pose: Pose2, goal: &rovernav_core::Goal, draw: bool) {
        let Some(view) = self.view.as_ref() else { return };
        let terrain = self.growth_terrain();
        self.obstacles = view.evaluator.layers().c_obstacles(&terrain, &view.wedges, Some(goal.position));
        self.obstacles.retain(|o| o.vertices.len() >= 3);
        let fresh = self.obstacles.len();
        // Carried ones keep the growth they were built with: after a squeeze the rover stands
        // within the buffer of the gap's rocks, and grown back they would hem it in again
        // (seeds 1..20 of the default yard: mean ratio 1.40 as kept, 1.51 regrown both ways,
        // 1.44 shrunk during a squeeze only); a nearer view supersedes them.
        self.obstacles.extend(self.carried.iter().cloned());
        self.sensed_len = self.obstacles.len();
        let top = self.top_obstacles(pose);
        self.obstacles.extend(top);
        if draw {
            for o in self.obstacles[..fresh].iter().chain(&self.obstacles[self.sensed_len..]) {
                self.drawn_obstacles.push(o.vertices.clone());
            }
        }
        self.obstacles.extend(self.contacts.iter().cloned());
        self.obstacles.extend(self.dead_ends.iter().cloned());
        // Keep-out zones are C-obstacles like any sensed one (their convex hulls, grown by the
        // same margin: conservative for a non-convex zone). They keep the safety buffer while
        // squeezing: the safety layer knows nothing of them.
        for zone in &goal.keep_out {
            let hull = rovernav_perception::hull::convex_hull(zone);
            if hull.len() >= 3 {
                self.obstacles.push(CObstacle::from_hull(
                    hull,
                    self.terrain.growth(),
                    self.terrain.max_arc_step,
                    0,
                ));
            }
        }
    }

    /// Drops the carried C-obstacles that the current view supersedes: those outside the
    /// mast's blind zone around the sensing position whose ground this view has sensed again
    /// (the centre and at least half the hull's vertices in sensed cells). The fresh ones are
    /// seen from nearer, so more accurately; stale copies would pile up and close gaps the
    /// nearer view shows open. Within the blind zone, or where this view has not looked, the
    /// carried ones stay.
    pub(super) fn supersede_carried(&mut self) {
        let Some(view) = &self.view else { return };
        let sensed = |p: Point2| view.evaluator.grid().at_world(p.x, p.y).is_some_and(|c| c.count > 0);
        let blind = self.config.paper.near_visible + self.config.paper.carry_margin;
        self.carried.retain(|o| {
            if o.hull.is_empty() || hull_distance(o, view.origin) < blind {
                return true;
            }
            let seen = o.hull.iter().filter(|&&p| sensed(p)).count();
            let centre =
                o.hull.iter().fold(Point2::new(0.0, 0.0), |a, &p| a.add(p)).scale(1.0 / o.hull.len() as f64);
            !(sensed(centre) && 2 * seen >= o.hull.len())
        });
    }
}

/// Euclidean distance from `p` to a C-obstacle's hull (the hazard cells' convex hull, before
/// growth); 0 inside it.
pub(super) fn hull_distance(o: &CObstacle, p: Point2) -> f64 {
    let n = o.hull.len();
    if n == 0 {
        return f64::INFINITY;
    }
    if n >= 3 && o.hull_contains_strict(p) {
        return 0.0;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (o.hull[i], o.hull[(i + 1) % n]);
            let d = b.sub(a);
            let t = if d.dot(d) > 1e-18 { (p.sub(a).dot(d) / d.dot(d)).clamp(0.0, 1.0) } else { 0.0 };
            p.dist(a.add(d.scale(t)))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The outline of a sensed wedge in the world, for display.
fn wedge_polygon(pose: Pose2, wedge: &rovernav_core::Wedge) -> Vec<Point2> {
    let n = 8;
    let mut out = Vec::with_capacity(2 * n + 2);
    for i in 0..=n {
        let a = wedge.bearing - wedge.half_angle + 2.0 * wedge.half_angle * i as f64 / n as f64;
        out.push(pose.transform(Point2::new(a.cos(), a.sin()).scale(wedge.max_range)));
    }
    for i in (0..=n).rev() {
        let a = wedge.bearing - wedge.half_angle + 2.0 * wedge.half_angle * i as f64 / n as f64;
        out.push(pose.transform(Point2::new(a.cos(), a.sin()).scale(wedge.min_range)));
    }
    out
}
