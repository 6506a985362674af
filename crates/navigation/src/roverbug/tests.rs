//! Unit tests of RoverBug on hand-built scenes, each against a hand-computed truth.

use super::unseen::first_unseen_pose;
use super::view::hull_distance;
use super::*;
use std::f64::consts::PI;

fn square(cx: f64, cy: f64, h: f64) -> CObstacle {
    let hull = vec![
        Point2::new(cx - h, cy - h),
        Point2::new(cx + h, cy - h),
        Point2::new(cx + h, cy + h),
        Point2::new(cx - h, cy + h),
    ];
    CObstacle::from_hull(hull, 0.0, 0.5, 1)
}

/// [`square`] with each corner once: a zero growth repeats the corners, whose zero-length
/// edges then pass any line as tangent.
fn corner_square(cx: f64, cy: f64, h: f64) -> CObstacle {
    let mut o = square(cx, cy, h);
    o.vertices = o.hull.clone();
    o.labels.truncate(o.vertices.len());
    o
}

fn bug_with(obstacles: Vec<CObstacle>) -> RoverBug {
    let mut bug = RoverBug::new(RoverConfig::default(), RoverBugConfig::default());
    bug.new_view(Pose2::new(0.0, 0.0, 0.0));
    let wedge = rovernav_core::Wedge { bearing: 0.0, half_angle: 1.2, min_range: 0.0, max_range: 5.0 };
    bug.view.as_mut().unwrap().wedges.push(SensedWedge { pose: Pose2::new(0.0, 0.0, 0.0), wedge });
    bug.obstacles = obstacles;
    bug
}

#[test]
fn ltg_path_around_a_square_is_the_hand_computed_tangent_path() {
    // Square [2,3]x[-0.5,0.5] between rover (0,0) and goal (4,0): the shortest path hugs one
    // side: 0 -> (2,±0.5) -> (3,±0.5) -> goal, by hand |(2,0.5)| + 1 + |(1,0.5)| = 4.1796.
    let bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
    let goal = Point2::new(4.0, 0.0);
    let ltg = bug.build_ltg(Point2::new(0.0, 0.0), goal);
    let path = bug.search(&ltg, goal, &|_| true).expect("path");
    let pts: Vec<Point2> = path.iter().map(|&i| ltg.nodes[i].p).collect();
    let len: f64 = pts.windows(2).map(|w| w[0].dist(w[1])).sum::<f64>() + pts.last().unwrap().dist(goal);
    let expect = 2.0f64.hypot(0.5) + 1.0 + 1.0f64.hypot(0.5);
    assert!((len - expect).abs() < 1e-3, "{len} vs {expect}: {pts:?}");
}

#[test]
fn d_reach_is_taken_on_the_near_side_of_the_boundary() {
    // Square [2,3]x[-0.5,0.5] between the rover (0,0) and the goal (4,0). Its near corners
    // (2,±0.5) are seen across free space, 2.0616 m from the goal; its far corners (3,±0.5)
    // are in view too (a mast sees over low rocks) but only past the square, 1.1180 m from
    // the goal. d_reach is the near corners' distance, not the far ones'; the target is the
    // near corner in the positive sense and V_loop, the extreme vertex in the negative sense,
    // the other near corner (the ring scenario `goal_inside_a_ring_of_rocks_is_unreachable`
    // is the one that tells a near-side V_loop from one among all vertices).
    let goal = Point2::new(4.0, 0.0);
    let x = Point2::new(0.0, 0.0);
    let bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
    let (path, d_reach, v_loop) = bug.silhouette(x, goal, 1.0, false).expect("a boundary vertex");
    assert!(path.last().unwrap().dist(Point2::new(2.0, 0.5)) < 1e-9, "{path:?}");
    assert!((d_reach - 2.0f64.hypot(0.5)).abs() < 1e-9, "{d_reach}");
    assert!(v_loop.dist(Point2::new(2.0, -0.5)) < 1e-9, "{v_loop:?}");
}

#[test]
fn a_goal_ringed_by_rocks_is_reached_within_its_tolerance() {
    // Eight squares of half-side 0.2 m centred 0.4 m around the goal (3, 0) overlap into a
    // closed ring: no path reaches the goal point. With a 1 m tolerance the circle of
    // arrival (0.8 m) lies outside the ring; the nearest point, (2.2, 0), is 2.2 m
    // straight ahead of the rover at the origin.
    let goal = Point2::new(3.0, 0.0);
    let ring: Vec<CObstacle> = (0..8)
        .map(|k| {
            let a = k as f64 * PI / 4.0;
            square(goal.x + 0.4 * a.cos(), goal.y + 0.4 * a.sin(), 0.2)
        })
        .collect();
    let mut bug = bug_with(ring);
    let x = Point2::new(0.0, 0.0);
    let plan = |bug: &RoverBug| {
        let ltg = bug.build_ltg(x, goal);
        bug.search(&ltg, goal, &|_| true).map(|path| path.iter().map(|&i| ltg.nodes[i]).collect::<Vec<_>>())
    };
    assert!(plan(&bug).is_none(), "the goal point is out of reach");
    bug.goal_tolerance = 1.0;
    let path = plan(&bug).expect("a path onto the circle of arrival");
    let end = path.last().unwrap();
    assert!(end.on_goal_circle());
    let length: f64 = path.windows(2).map(|w| w[0].p.dist(w[1].p)).sum();
    assert!((length - 2.2).abs() < 1e-9 && (end.p.dist(goal) - 0.8).abs() < 1e-9, "{path:?}");
    // In open ground the path runs straight toward the goal, onto the circle.
    let mut open = bug_with(vec![]);
    open.goal_tolerance = 1.0;
    let ltg = open.build_ltg(x, goal);
    let path = open.search(&ltg, goal, &|_| true).expect("path");
    assert_eq!(path.len(), 2);
    assert!(ltg.nodes[path[1]].p.dist(Point2::new(2.2, 0.0)) < 1e-9);
    // A small tolerance keeps the hop onto its circle above the shortest subpath.
    open.goal_tolerance = 0.3;
    let ltg = open.build_ltg(Point2::new(2.69, 0.0), goal);
    let circle: Vec<_> = ltg.nodes.iter().filter(|n| n.on_goal_circle()).collect();
    assert!(!circle.is_empty() && circle.iter().all(|n| (n.p.dist(goal) - 0.15).abs() < 1e-9));
}

#[test]
fn from_a_margin_the_rover_may_cross_the_margin_but_not_the_hull() {
    // Hull [1,2]x[-0.5,0.5] grown by 0.6: the rover at (0.6, 0) is 0.4 m from the hull, in
    // the margin. Sideways or back it never crosses the hull; straight on it does.
    let hull =
        vec![Point2::new(1.0, -0.5), Point2::new(2.0, -0.5), Point2::new(2.0, 0.5), Point2::new(1.0, 0.5)];
    let bug = bug_with(vec![CObstacle::from_hull(hull, 0.6, 30f64.to_radians(), 4)]);
    let x = Point2::new(0.6, 0.0);
    assert!(bug.obstacles[0].contains_strict(x));
    assert!(bug.segment_free(x, Point2::new(-1.0, 0.0), x));
    assert!(bug.segment_free(x, Point2::new(0.6, -3.0), x));
    assert!(!bug.segment_free(x, Point2::new(3.0, 0.0), x));
    // The same segments from anywhere but the rover's position are blocked.
    assert!(!bug.segment_free(x, Point2::new(0.6, -3.0), Point2::new(-1.0, 0.0)));
    // Inside the hull itself every way out crosses the hazard.
    let inside = Point2::new(1.5, 0.0);
    assert!(!bug.segment_free(inside, Point2::new(1.5, -3.0), inside));
    assert!(!bug.segment_free(inside, Point2::new(-1.0, 0.0), inside));
}

#[test]
fn from_a_recorded_contact_the_rover_may_not_go_deeper() {
    // A contact at the origin grown by 0.6; the rover 0.3 m east of it backs away freely but
    // may not drive across the contact point.
    let contact = CObstacle::from_hull(vec![Point2::new(0.0, 0.0)], 0.6, 30f64.to_radians(), 0);
    let bug = bug_with(vec![contact]);
    let x = Point2::new(0.3, 0.0);
    assert!(bug.segment_free(x, Point2::new(2.0, 0.0), x));
    assert!(!bug.segment_free(x, Point2::new(-2.0, 0.0), x));
}

#[test]
fn t_g_is_added_only_when_the_line_to_the_goal_is_free() {
    let goal = Point2::new(4.0, 0.0);
    let free = bug_with(vec![square(2.5, 2.0, 0.5)]);
    assert!(free.build_ltg(Point2::new(0.0, 0.0), goal).nodes.iter().any(|n| n.p.dist(goal) < 1e-9));
    let blocked = bug_with(vec![square(2.5, 0.0, 0.5)]);
    assert!(!blocked.build_ltg(Point2::new(0.0, 0.0), goal).nodes.iter().any(|n| n.p.dist(goal) < 1e-9));
}

#[test]
fn truncation_stops_at_the_far_radius_minus_buffer() {
    let bug = bug_with(vec![]);
    let x = Point2::new(0.0, 0.0);
    let cut = bug.truncate(&[x, Point2::new(3.0, 0.0), Point2::new(3.0, 10.0)], x);
    let last = *cut.last().unwrap();
    assert!((last.dist(x) - 4.0).abs() < 1e-9);
    assert!((last.x - 3.0).abs() < 1e-9 && (last.y - 7f64.sqrt()).abs() < 1e-9);
}

#[test]
fn arc_poses_follow_the_circle_of_the_curvature() {
    // Curvature 0.5 (radius 2) driven for half the circumference from the origin heading
    // +x ends 4 m to the left, heading -x; a straight drive ends on the heading line.
    let start = Pose2::new(0.0, 0.0, 0.0);
    let end = *RoverBug::arc_poses(start, PI * 2.0, 0.5).last().unwrap();
    assert!(end.x.abs() < 1e-9 && (end.y - 4.0).abs() < 1e-9, "{end:?}");
    assert!(angle_diff(end.yaw, PI).abs() < 1e-9);
    let back = *RoverBug::arc_poses(Pose2::new(1.0, 1.0, 0.5 * PI), -2.0, 0.0).last().unwrap();
    assert!((back.x - 1.0).abs() < 1e-9 && (back.y + 1.0).abs() < 1e-9, "{back:?}");
}

/// A navigator at the origin heading +x whose safety layer holds the given hazard cells.
fn bug_with_hazards(cells: &[(f64, f64)]) -> RoverBug {
    let mut bug = bug_with(vec![]);
    let geometry =
        rovernav_core::GridGeometry { cols: 60, rows: 60, resolution: 0.1, origin_x: -3.0, origin_y: -3.0 };
    let mut grid = Grid2::filled(geometry, false);
    for &(x, y) in cells {
        let (c, r) = geometry.cell_of(x, y).unwrap();
        *grid.get_mut(c, r) = true;
    }
    bug.safety_hazard = Some(grid);
    bug
}

#[test]
fn motion_check_follows_the_body_outline() {
    // Default body 0.8 x 0.6 m, margin 0.08 m. A cell 0.45 m to the left of the centre is
    // 0.15 m from the body's side: driving straight keeps it there, a quarter turn brings
    // the front end to 0.05 m of it.
    let start = Pose2::new(0.0, 0.0, 0.0);
    let beside = bug_with_hazards(&[(0.05, 0.45)]);
    assert!(beside.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).is_empty());
    assert!(beside.motion_hazards(start, &RoverBug::arc_poses(start, -1.0, 0.0)).is_empty());
    assert_eq!(beside.motion_hazards(start, &RoverBug::turn_poses(start, 0.5 * PI)).len(), 1);
    // A cell 0.95 m ahead is met driving 1 m forward, not backward.
    let ahead = bug_with_hazards(&[(0.95, 0.05)]);
    assert_eq!(ahead.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).len(), 1);
    assert!(ahead.motion_hazards(start, &RoverBug::arc_poses(start, -1.0, 0.0)).is_empty());
    // A cell under the body where the rover stands never counts.
    let under = bug_with_hazards(&[(0.15, 0.05)]);
    assert!(under.motion_hazards(start, &RoverBug::turn_poses(start, PI)).is_empty());
    assert!(under.motion_hazards(start, &RoverBug::arc_poses(start, 1.0, 0.0)).is_empty());
}

#[test]
fn c_obstacles_grow_by_the_circumscribed_radius_plus_the_safety_buffer() {
    // Paper 000 section 2: the rover as its circumscribed disc; the 0.8 x 0.6 m body's radius
    // is 0.5 m, and the default buffer 0.1 m.
    let rover = RoverConfig::default();
    let terrain = c_obstacle_terrain(&rover, &RoverBugConfig::default());
    assert!((terrain.growth() - (0.5 * 0.8f64.hypot(0.6) + 0.1)).abs() < 1e-12);
}

/// A 45-degree mast wedge along +x from the origin, sensed from 1 to 5 m.
fn wedge_sensed(q: Point2) -> bool {
    (1.0..=5.0).contains(&q.norm()) && q.y.atan2(q.x).abs() <= 22.5f64.to_radians()
}

#[test]
fn a_drive_along_the_wedge_edge_meets_unseen_ground_within_a_metre_and_one_along_its_axis_none() {
    let (half, blind) = ((0.5, 0.3), |q: Point2| q.norm() <= 1.0);
    let axis = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 0.0), 4.0, 0.0);
    assert_eq!(first_unseen_pose(&axis, half, 0.1, blind, wedge_sensed), None);
    // 2.5 degrees inside the edge, the body's left side leaves the wedge as soon as it is
    // out of the blind zone (seed 49 of the default yard met a 0.38 m rock there).
    let edge = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 20f64.to_radians()), 4.0, 0.0);
    let k = first_unseen_pose(&edge, half, 0.1, blind, wedge_sensed).expect("the body leaves the wedge");
    assert!(edge[k].position().norm() < 1.0, "met at {:?}", edge[k]);
}

#[test]
fn a_one_row_gap_in_the_sensed_ground_passes_and_a_two_row_gap_stops_the_body_front() {
    let axis = RoverBug::arc_poses(Pose2::new(0.0, 0.0, 0.0), 3.0, 0.0);
    let column = |q: Point2| (q.x / 0.1).floor() as i64;
    let one = |q: Point2| column(q) != 20;
    assert_eq!(first_unseen_pose(&axis, (0.5, 0.3), 0.1, |_| false, one), None);
    let two = |q: Point2| !matches!(column(q), 20 | 21);
    let k = first_unseen_pose(&axis, (0.5, 0.3), 0.1, |_| false, two).expect("a two-row gap is unseen");
    // The outline's front (0.5 m ahead of the centre) reaches the gap's first cell centres
    // (x = 2.05 m); the poses are 5 cm apart.
    assert!((1.55..=1.6).contains(&axis[k].x), "met at {:?}", axis[k]);
    // Exempt ground (in the navigator: under the body where it stands) never counts.
    assert_eq!(first_unseen_pose(&axis, (0.5, 0.3), 0.1, |q| q.x > 1.9, two), None);
}

#[test]
fn hull_distance_is_the_euclidean_distance_to_the_hull() {
    let o = square(0.0, 0.0, 1.0);
    assert_eq!(hull_distance(&o, Point2::new(0.2, -0.3)), 0.0);
    assert!((hull_distance(&o, Point2::new(3.0, 0.5)) - 2.0).abs() < 1e-9);
    // Off a corner the distance is to the corner, not to the edge's line.
    assert!((hull_distance(&o, Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-9);
    let point = CObstacle::from_hull(vec![Point2::new(1.0, 1.0)], 0.6, 30f64.to_radians(), 0);
    assert!((hull_distance(&point, Point2::new(4.0, 5.0)) - 5.0).abs() < 1e-9);
}

#[test]
fn carried_obstacles_give_way_only_where_the_new_view_sensed_their_ground_again() {
    use rovernav_core::{CameraKind, PointCloud, Pose3, PoseEstimate, Wedge};
    let mut bug = bug_with(vec![]);
    // Flat ground sensed from the origin over x in [0.5, 4], y in [-1, 1].
    let points: Vec<[f32; 3]> = (0..70)
        .flat_map(|i| (0..40).map(move |j| [0.5 + 0.05 * i as f32, -1.0 + 0.05 * j as f32, 0.0]))
        .collect();
    let wedge = Wedge { bearing: 0.0, half_angle: 0.6, min_range: 0.5, max_range: 5.0 };
    let cloud = PointCloud { camera: CameraKind::Mast, origin: [0.0; 3], wedge, points };
    let estimate = PoseEstimate { pose: Pose3::default(), covariance: [[0.0; 3]; 3] };
    bug.view.as_mut().unwrap().evaluator.update(&[cloud], &estimate);
    // Sensed again beyond the blind zone; sensed but within the blind zone (1.2 m); never
    // looked at.
    bug.carried = vec![square(3.0, 0.0, 0.2), square(0.9, 0.0, 0.2), square(3.0, 3.0, 0.2)];
    bug.supersede_carried();
    let centres: Vec<Point2> = bug
        .carried
        .iter()
        .map(|o| o.hull.iter().fold(Point2::new(0.0, 0.0), |a, &p| a.add(p)).scale(0.25))
        .collect();
    assert_eq!(centres.len(), 2, "{centres:?}");
    assert!(centres[0].dist(Point2::new(0.9, 0.0)) < 1e-9);
    assert!(centres[1].dist(Point2::new(3.0, 3.0)) < 1e-9);
}

#[test]
fn a_retreat_retraces_the_trail_and_records_the_dead_end() {
    let mut bug = bug_with(vec![]);
    // An L-shaped trail: 1 m east, then 2 m north to the rover at (1, 2).
    bug.trail = vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0), Point2::new(1.0, 1.0)];
    let x = Point2::new(1.0, 2.0);
    assert!(bug.retreat(x, Point2::new(9.0, 9.0)));
    // Back through (1, 1) to (1, 0): 2 m, the first trail point at least 1.5 m back.
    let wp: Vec<Point2> = bug.waypoints.iter().copied().collect();
    assert_eq!(wp, vec![Point2::new(1.0, 1.0), Point2::new(1.0, 0.0)]);
    assert!(bug.reversing);
    assert_eq!(bug.mode, Mode::MotionToGoal);
    assert!(bug.dead_ends.len() == 1 && bug.dead_ends[0].contains_strict(x));
    // The retraced part leaves the trail; its end stays.
    assert_eq!(bug.trail, vec![Point2::new(0.0, 0.0), Point2::new(1.0, 0.0)]);
    // Reversing, the executor drives the rear to the waypoint along an arc.
    bug.waypoints = VecDeque::from(vec![Point2::new(-1.0, 0.1)]);
    let pose = Pose2::new(0.0, 0.0, 0.0);
    let NavCommand::Drive { distance, curvature, .. } = bug.drive_waypoints(pose, Point2::new(9.0, 9.0))
    else {
        panic!("a reverse drive expected");
    };
    assert!(distance < 0.0);
    let end = *RoverBug::arc_poses(pose, distance, curvature).last().unwrap();
    assert!(end.position().dist(Point2::new(-1.0, 0.1)) < 1e-9, "{end:?}");
    // Too short a trail, or the retreats used up: no retreat.
    let mut short = bug_with(vec![]);
    short.trail = vec![Point2::new(0.0, 0.1)];
    assert!(!short.retreat(Point2::new(0.0, 0.0), Point2::new(9.0, 9.0)));
    bug.retreats = bug.config.recovery.max_retreats;
    bug.trail = vec![Point2::new(0.0, 0.0), Point2::new(5.0, 0.0)];
    assert!(!bug.retreat(Point2::new(5.0, 3.0), Point2::new(9.0, 9.0)));
}

/// Smallest distance of a point from the body outline over the poses (Chebyshev-style, as
/// the safety check measures it; negative under the body), computed here independently.
fn body_clearance(rover: &RoverConfig, poses: &[Pose2], q: Point2) -> f64 {
    poses
        .iter()
        .map(|p| {
            let b = p.inverse_transform(q);
            (b.x.abs() - 0.5 * rover.length).max(b.y.abs() - 0.5 * rover.width)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn seed_14_a_retreat_pinned_against_turning_backs_along_an_arc() {
    // Hazard cells (at their grid centres) 0.45 m either side of the rover's centre: 0.15 m
    // off its sides, but a turn in place of 30 degrees either way brings a corner within
    // the 0.08 m margin.
    let cells = [(0.05, 0.45), (0.05, -0.45)];
    let mut bug = bug_with_hazards(&cells);
    let rover = bug.rover.clone();
    let m = bug.config.safety.body_margin;
    let pose = Pose2::new(0.0, 0.0, 0.0);
    // The retreat's waypoint 2 m away, 30 degrees off the rear.
    let a = 150f64.to_radians();
    let wp = Point2::new(2.0 * a.cos(), 2.0 * a.sin());
    let near = |poses: &[Pose2]| {
        cells
            .iter()
            .map(|&(x, y)| body_clearance(&rover, poses, Point2::new(x, y)))
            .fold(f64::INFINITY, f64::min)
    };
    // Truth: both turns in place toward it pass the cells within the margin.
    let turn = -30f64.to_radians();
    assert!(near(&RoverBug::turn_poses(pose, turn)) < m);
    assert!(near(&RoverBug::turn_poses(pose, turn + 2.0 * PI)) < m);
    bug.reversing = true;
    bug.waypoints = VecDeque::from(vec![wp]);
    let NavCommand::Drive { distance, curvature, .. } = bug.drive_waypoints(pose, Point2::new(9.0, 9.0))
    else {
        panic!("a reverse arc expected, not a refusal");
    };
    assert!(distance < 0.0);
    let poses = RoverBug::arc_poses(pose, distance, curvature);
    let end = *poses.last().unwrap();
    assert!(end.position().dist(wp) < 1e-9, "{end:?}");
    // The rear leads all the way: the end heading points the front away from the start.
    assert!(angle_diff(end.yaw, wp.angle() + PI).abs() < 0.55, "{end:?}");
    assert!(near(&poses) >= m, "the arc sweeps within {} m of a cell", near(&poses));
    // Driving forward, the same refusal stands (only retreats back along an arc).
    bug.reversing = false;
    bug.waypoints = VecDeque::from(vec![Point2::new(2.0 * 30f64.to_radians().cos(), -1.0)]);
    assert!(!matches!(bug.drive_waypoints(pose, Point2::new(9.0, 9.0)), NavCommand::Drive { .. }));
}

/// The first waypoint of the best way on from the origin toward `goal`.
fn first_exit_waypoint(bug: &RoverBug, goal: Point2) -> Point2 {
    let x = Point2::new(0.0, 0.0);
    let path = bug.best_exit(&bug.build_ltg(x, goal), x, goal).expect("a way on");
    path[1]
}

#[test]
fn seed_4_boundary_following_memory_survives_a_restart() {
    // Square [2,3]x[-0.5,0.5] across the line to a goal a little left of the axis: by hand
    // the way on passes the upper corners (path plus remaining distance 6.07 m against
    // 6.12 m by the lower ones). Once boundary following has restarted at both upper
    // corners (escapes from there), a new restart must not lead back to them: the only
    // nodes left are the lower corners.
    let goal = Point2::new(6.0, 0.2);
    let x = Point2::new(0.0, 0.0);
    let mut bug = bug_with(vec![square(2.5, 0.0, 0.5)]);
    assert!(first_exit_waypoint(&bug, goal).y > 0.0);
    bug.start_boundary_following(x, goal);
    bug.remember(Point2::new(2.0, 0.5));
    bug.remember(Point2::new(3.0, 0.5));
    bug.start_boundary_following(x, goal);
    assert_eq!(bug.visited, vec![x], "a restart begins a new segment");
    let wp = first_exit_waypoint(&bug, goal);
    assert!(wp.y < 0.0 && (wp.x - 2.0).abs() < 1e-6, "{wp:?}");
    // With the lower corners remembered too, every way on is near a restart point: one
    // near them still beats halting.
    bug.remember(Point2::new(2.0, -0.5));
    bug.remember(Point2::new(3.0, -0.5));
    let ltg = bug.build_ltg(x, goal);
    assert!(bug.best_exit_avoiding(&ltg, x, goal, &bug.been).is_none());
    assert!(bug.best_exit(&ltg, x, goal).is_some());
    // Motion to goal from the start plans round the upper corners again: not progress
    // past the restart points, which stay remembered.
    let remembered = bug.been.len();
    assert!(bug.motion_to_goal(x, goal));
    assert_eq!(bug.been.len(), remembered);
    // From beyond the square its subpath ends nearer the goal than every restart point:
    // they are forgotten, and the upper side is open again.
    assert!(bug.motion_to_goal(Point2::new(4.0, 0.0), goal));
    assert!(bug.been.is_empty());
    bug.visited.clear();
    assert!(first_exit_waypoint(&bug, goal).y > 0.0);
}

#[test]
fn seed_10_boundary_following_fallback_turned_away_from_the_goal() {
    // Square [2,3]x[-0.5,0.5] across the line to the goal (6,0), and a square
    // [1.2,1.8]x[1.7,2.3] off to the left. By hand, the nodes joined to the rover are the
    // near corners (2,±0.5) at ±14.0 degrees from the goal direction and the left square's
    // silhouette corners (1.8,1.7) at 43.4 and (1.2,2.3) at 62.4 degrees. Counter-clockwise
    // the fallback hugs the blocking square at (2,0.5); turning as far as possible it took
    // (1.2,2.3), away from the goal.
    let goal = Point2::new(6.0, 0.0);
    let x = Point2::new(0.0, 0.0);
    let mut bug = bug_with(vec![corner_square(2.5, 0.0, 0.5), corner_square(1.5, 2.0, 0.3)]);
    let step =
        |bug: &RoverBug, s: f64| bug.fallback_step(&bug.build_ltg(x, goal), x, goal, s).expect("a step")[1];
    let near = |a: Point2, b: Point2| a.dist(b) < 1e-6;
    assert!(near(step(&bug, 1.0), Point2::new(2.0, 0.5)), "{:?}", step(&bug, 1.0));
    assert!(near(step(&bug, -1.0), Point2::new(2.0, -0.5)), "{:?}", step(&bug, -1.0));
    // With that corner visited, the next one round in the positive sense.
    bug.visited = vec![x, Point2::new(2.0, 0.5)];
    assert!(near(step(&bug, 1.0), Point2::new(1.8, 1.7)), "{:?}", step(&bug, 1.0));
    // Nothing left on the positive side: a node on the other.
    bug.visited.extend([Point2::new(1.8, 1.7), Point2::new(1.2, 2.3)]);
    assert!(near(step(&bug, 1.0), Point2::new(2.0, -0.5)), "{:?}", step(&bug, 1.0));
}

#[test]
fn seed_19_far_from_d_reach_the_blocked_step_heads_for_the_goal() {
    // Square [2,3]x[-0.5,0.5] across the line to the goal (6,-0.2). By hand, the way on by
    // the lower corners (path plus remaining distance 2.062 + 1 + 3.015 = 6.077 m) beats
    // the upper ones (6.142 m); counter-clockwise, the wall follower's step is the upper
    // corner (2,0.5), the first past the goal direction.
    let goal = Point2::new(6.0, -0.2);
    let x = Point2::new(0.0, 0.0);
    let scene = || bug_with(vec![corner_square(2.5, 0.0, 0.5)]);
    let bug = scene();
    let d = x.dist(goal);
    let ltg = bug.build_ltg(x, goal);
    let step = |d_reach: f64| bug.blocked_step(&ltg, x, goal, 1.0, d_reach).expect("a step")[1];
    let near = |a: Point2, b: Point2| a.dist(b) < 1e-6;
    // Within the limit of d_reach: along the boundary.
    assert!(near(step(d - 1.0), Point2::new(2.0, 0.5)), "{:?}", step(d - 1.0));
    // Led farther than the limit (2 m) from it: toward the goal.
    assert!(near(step(d - 2.5), Point2::new(2.0, -0.5)), "{:?}", step(d - 2.5));
    // Disabled, along the boundary however far.
    let mut off = scene();
    off.config.recovery.wander_limit = 0.0;
    assert!(near(off.blocked_step(&ltg, x, goal, 1.0, d - 2.5).expect("a step")[1], Point2::new(2.0, 0.5)));
}

#[test]
fn a_loop_proves_unreachable_only_around_the_goal() {
    let goal = Point2::new(0.0, 0.0);
    let circle = |c: Point2, r: f64, turn: f64| -> Vec<Point2> {
        (0..=24)
            .map(|k| k as f64 * turn / 24.0)
            .map(|t| c.add(Point2::new(t.cos(), t.sin()).scale(r)))
            .collect()
    };
    let mut bug = bug_with(vec![]);
    // 330 degrees around the goal.
    bug.visited = circle(goal, 3.0, 330f64.to_radians());
    assert!(bug.encircles_goal(goal, None));
    // Half a turn around it is no loop yet.
    bug.visited = circle(goal, 3.0, PI);
    assert!(!bug.encircles_goal(goal, None));
    // A full loop around a point 5 m away leaves the goal outside.
    bug.visited = circle(Point2::new(5.0, 0.0), 2.0, 2.0 * PI);
    assert!(!bug.encircles_goal(goal, None));
}
