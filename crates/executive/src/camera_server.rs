//! The camera server: serves the platform's camera images to whoever needs them and judges
//! each camera's health from its pixels alone.
//!
//! The platform reports the images of a command in its frame; the server publishes each one
//! on `/camera/image` (the topic later consumers — target tracking, the science detectors, the
//! operator's camera panels — subscribe to) and goes to Failure when a camera returns
//! [`BLIND_IMAGES`] images in a row without contrast (every pixel within [`BLIND_SPREAD_DN`] of
//! the others: a dead detector, a stuck shutter, a covered lens), which stereo would otherwise
//! read as "no range here" forever.

use crate::components::{Component, ComponentFault, Ctx, JausState, Port, Ports};
use crate::messages::{FrameMsg, ImageMsg, topics};
use rovernav_bus::{Bus, BusError, Subscriber};
use std::collections::BTreeMap;

/// Images in a row without contrast after which a camera is declared blind.
pub const BLIND_IMAGES: u32 = 3;
/// Largest spread of pixel values (DN) that counts as no contrast.
pub const BLIND_SPREAD_DN: u16 = 2;

/// Serves camera images and watches for blind cameras.
#[derive(Default)]
pub struct CameraServer {
    frames: Option<Subscriber<FrameMsg>>,
    /// Each camera's current run of images without contrast.
    blind_in_a_row: BTreeMap<String, u32>,
}

impl CameraServer {
    /// A server with clean counts.
    pub fn new() -> Self {
        Self::default()
    }

    fn serve(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        let frames = match &self.frames {
            Some(s) => ctx.bus.take(s)?,
            None => Vec::new(),
        };
        for frame in frames {
            for image in &frame.images {
                self.check(image)?;
                ctx.bus.publish(topics::CAMERA_IMAGE, image.clone())?;
            }
        }
        Ok(())
    }

    fn check(&mut self, image: &ImageMsg) -> Result<(), ComponentFault> {
        let expected = image.width as usize * image.height as usize;
        if image.pixels.len() != expected {
            return Err(ComponentFault(format!(
                "camera {}: {} pixels for a {}x{} image",
                image.camera,
                image.pixels.len(),
                image.width,
                image.height
            )));
        }
        let (lo, hi) = image.pixels.iter().fold((u16::MAX, 0), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let run = self.blind_in_a_row.entry(image.camera.clone()).or_default();
        if expected > 0 && hi.saturating_sub(lo) > BLIND_SPREAD_DN {
            *run = 0;
            return Ok(());
        }
        *run += 1;
        if *run >= BLIND_IMAGES {
            return Err(ComponentFault(format!(
                "camera blind: {} returned {} images in a row without contrast (DN {lo}..{hi})",
                image.camera, run
            )));
        }
        Ok(())
    }
}

impl Component for CameraServer {
    fn name(&self) -> &'static str {
        "camera-server"
    }
    fn ports(&self) -> Ports {
        Ports {
            inputs: vec![Port::of(topics::PLATFORM_FRAME)],
            outputs: vec![Port::of(topics::CAMERA_IMAGE)],
        }
    }
    fn connect(&mut self, bus: &mut Bus) -> Result<(), BusError> {
        self.frames = Some(bus.subscribe(topics::PLATFORM_FRAME)?);
        Ok(())
    }
    fn step(&mut self, ctx: &mut Ctx<'_>) -> Result<(), ComponentFault> {
        self.serve(ctx)
    }
    fn idle(&mut self, ctx: &mut Ctx<'_>, _state: JausState) -> Result<(), ComponentFault> {
        self.serve(ctx)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::messages::FrameSource;

    fn frame(images: Vec<ImageMsg>) -> FrameMsg {
        FrameMsg {
            seq: 1,
            source: FrameSource::Hold,
            frame: rovernav_core::SensorFrame { images, ..Default::default() },
        }
    }

    fn image(camera: &str, pixels: Vec<u16>) -> ImageMsg {
        ImageMsg { camera: camera.into(), t: 0.0, width: 2, height: 2, bits: 12, pixels, pan: 0.0, tilt: 0.0 }
    }

    /// Feeds frames one step each; the images served and the fault, if any.
    fn feed(frames: Vec<FrameMsg>) -> (Vec<ImageMsg>, Option<String>) {
        let mut bus = Bus::in_process();
        let mut server = CameraServer::new();
        server.connect(&mut bus).unwrap();
        let served = bus.subscribe(topics::CAMERA_IMAGE).unwrap();
        let mut fault = None;
        for f in frames {
            bus.publish(topics::PLATFORM_FRAME, f).unwrap();
            if let Err(ComponentFault(why)) = server.step(&mut Ctx { bus: &mut bus, time_s: 0.0 }) {
                fault = Some(why);
                break;
            }
        }
        let images = bus.take(&served).unwrap().iter().map(|i| (**i).clone()).collect();
        (images, fault)
    }

    #[test]
    fn images_are_served_in_order() {
        let a = image("navcam_left", vec![10, 900, 20, 4000]);
        let b = image("hazcam_front_left", vec![0, 1, 2, 3]);
        let (served, fault) = feed(vec![frame(vec![a.clone()]), frame(vec![b.clone()])]);
        assert_eq!(fault, None);
        assert_eq!(served, vec![a, b]);
    }

    #[test]
    fn a_camera_without_contrast_three_times_running_is_blind_and_contrast_resets_the_count() {
        let flat = |v: u16| image("navcam_left", vec![v, v + 1, v, v]);
        let textured = image("navcam_left", vec![0, 500, 1000, 4095]);
        let (_, fault) =
            feed(vec![frame(vec![flat(0)]), frame(vec![flat(7)]), frame(vec![textured.clone()])]);
        assert_eq!(fault, None, "two flat images then contrast is healthy");
        let (_, fault) = feed(vec![frame(vec![flat(0)]), frame(vec![flat(0)]), frame(vec![flat(4094)])]);
        let why = fault.expect("three flat images fail");
        assert!(why.contains("navcam_left") && why.contains("3 images"), "{why}");
        // Another camera's flat images count on their own.
        let other = image("hazcam_front_left", vec![5, 5, 5, 5]);
        let (_, fault) = feed(vec![
            frame(vec![flat(0), textured.clone()]),
            frame(vec![other.clone()]),
            frame(vec![other]),
        ]);
        assert_eq!(fault, None);
    }

    #[test]
    fn a_short_image_is_a_fault_naming_the_camera() {
        let (_, fault) = feed(vec![frame(vec![image("navcam_left", vec![1, 2, 3])])]);
        assert!(fault.unwrap().contains("3 pixels for a 2x2"));
    }
}
