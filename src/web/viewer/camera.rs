//! The orbit camera: yaw and pitch about a target, z up.

use glam::{Mat4, Vec3};

/// Orbit camera around a target, z up (angles in radians).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub yaw: f32,
    pub pitch: f32,
    pub distance: f32,
    pub target: Vec3,
    /// Radius of the scene, for clip planes.
    pub scene_radius: f32,
}

impl OrbitCamera {
    pub const FOV_Y: f32 = 0.7;

    pub fn framing(center: Vec3, radius: f32) -> Self {
        let radius = radius.max(1e-6);
        Self { yaw: -0.9, pitch: 0.55, distance: radius / (Self::FOV_Y * 0.5).tan() * 1.15, target: center, scene_radius: radius }
    }

    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * cy, cp * sy, sp)
    }

    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Z)
    }

    pub fn proj(&self, aspect: f32) -> Mat4 {
        // Keep far/near moderate: 24-bit depth must still order lines and faces.
        let far = self.distance + 4.0 * self.scene_radius;
        let near = (self.distance - 4.0 * self.scene_radius).max(0.01 * self.scene_radius).max(far * 1e-4);
        Mat4::perspective_rh(Self::FOV_Y, aspect.max(1e-3), near, far)
    }

    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw -= dx * 0.008;
        self.pitch = (self.pitch + dy * 0.008).clamp(-1.55, 1.55);
    }

    /// Pans by a screen-space drag of (dx, dy) points in a viewport `height` points tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let scale = 2.0 * self.distance * (Self::FOV_Y * 0.5).tan() / height.max(1.0);
        let view = self.view();
        let right = Vec3::new(view.x_axis.x, view.y_axis.x, view.z_axis.x);
        let up = Vec3::new(view.x_axis.y, view.y_axis.y, view.z_axis.y);
        self.target += (-dx * right + dy * up) * scale;
    }

    pub fn zoom(&mut self, factor: f32) {
        self.distance = (self.distance / factor.max(1e-3)).clamp(self.scene_radius * 1e-3, self.scene_radius * 1e3);
    }

    /// World-space ray through a point given in normalized device coordinates.
    pub fn ray(&self, ndc_x: f32, ndc_y: f32, aspect: f32) -> (Vec3, Vec3) {
        let inv = (self.proj(aspect) * self.view()).inverse();
        let a = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
        let b = inv.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
        (a, (b - a).normalize())
    }
}
