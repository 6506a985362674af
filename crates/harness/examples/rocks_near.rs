//! Lists the rocks near a point of a mission's world: `rocks_near SEED X Y [RADIUS]`.

use rovernav_executive::Mission;
use rovernav_harness::build_world;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: rocks_near SEED X Y [RADIUS]");
        std::process::exit(2);
    }
    let parse = |i: usize| args[i].parse::<f64>().unwrap_or_else(|_| panic!("argument {i} is not a number"));
    let mut mission = Mission::default_mission();
    mission.seed = parse(1) as u64;
    let (x, y) = (parse(2), parse(3));
    let radius = if args.len() > 4 { parse(4) } else { 1.0 };
    let world = build_world(&mission, "default").expect("default world builds");
    let ground = world.terrain.dem.height(x, y);
    println!("terrain height at ({x}, {y}): {ground:?}");
    for rock in &world.terrain.rocks {
        let d = (rock.x - x).hypot(rock.y - y);
        if d <= radius + rock.diameter / 2.0 {
            println!(
                "rock at ({:.2}, {:.2}) d={:.2} diameter {:.2} height {:.3}",
                rock.x, rock.y, d, rock.diameter, rock.height
            );
        }
    }
}
