//! Krang's actuators: the map from wheel and joint torques to the generalized forces of
//! the 19-speed model, and the motor/gear/limit data of the hardware.
//!
//! The actuator vector has 18 entries (indices in [`actuator`]):
//! `a = [τ_L, τ_R, τ_waist, τ_torso, τ_1l … τ_7l, τ_1r … τ_7r]`, the wheel motor torques
//! (on each wheel about the axle `j0`, positive driving the robot forward) and the 16 joint
//! torques (about each joint axis `e_j`, positive in the direction of positive `q̇_j`), all
//! in N·m at the output of the gearbox.
//!
//! From DynamicModeling.tex, §§ "Wheel Torques" and "Joint Torques" (Kane's right-hand side):
//!
//! | row | generalized force |
//! |-----|-------------------|
//! | ẋ | `(τ_L + τ_R) / R` |
//! | ψ̇ | `(L / 2R) (τ_R − τ_L)` |
//! | q̇_imu | `−(τ_L + τ_R)` (the wheel motors' reaction on the base) |
//! | q̇_w, q̇_torso, q̇_1l … q̇_7r | the joint's own torque (action and reaction cancel elsewhere) |
//!
//! The ψ̇ row follows the report's derivation (eq. `wheelTorque2`): its summary table
//! ("RHS Final Expressions") prints `(L/2R)(τ_L − τ_R)`, with the sign reversed. The sign used
//! here is the power-consistent one: with `B` = [`Krang::actuator_matrix`],
//! `Bᵀ u` are the actuator rates ([`Krang::actuator_velocities`]), e.g. the left wheel
//! relative to the base `θ̇_L − q̇_imu = ẋ/R − (L/2R) ψ̇ − q̇_imu`, and the actuator power
//! `aᵀ Bᵀ u` equals `(B a)ᵀ u`.
//!
//! `R` (wheel radius) and `L` (track width) come from the model's [`Params`](crate::Params).

use nalgebra::{SMatrix, SVector};

use crate::{Krang, index};

/// Number of actuators (2 wheels, waist, torso, 2 × 7 arm joints).
pub const ACTUATOR_COUNT: usize = 18;

/// Actuator names, in the order of the actuator vector.
pub const ACTUATOR_NAMES: [&str; ACTUATOR_COUNT] = [
    "tau_L",
    "tau_R",
    "tau_waist",
    "tau_torso",
    "tau_1l",
    "tau_2l",
    "tau_3l",
    "tau_4l",
    "tau_5l",
    "tau_6l",
    "tau_7l",
    "tau_1r",
    "tau_2r",
    "tau_3r",
    "tau_4r",
    "tau_5r",
    "tau_6r",
    "tau_7r",
];

/// Indices into the actuator vector.
pub mod actuator {
    /// Left wheel motor torque `τ_L`.
    pub const WHEEL_L: usize = 0;
    /// Right wheel motor torque `τ_R`.
    pub const WHEEL_R: usize = 1;
    /// Waist torque `τ_waist` (drives `q_w`).
    pub const WAIST: usize = 2;
    /// Torso torque `τ_torso` (drives `q_torso`).
    pub const TORSO: usize = 3;
    /// The left-arm joint torques `τ_1l … τ_7l` (a range, as
    /// [`forward::LEFT_ARM`](crate::forward::LEFT_ARM) is in `u`).
    pub const LEFT_ARM: core::ops::Range<usize> = 4..11;
    /// The right-arm joint torques `τ_1r … τ_7r` (a range, as
    /// [`forward::RIGHT_ARM`](crate::forward::RIGHT_ARM) is in `u`).
    pub const RIGHT_ARM: core::ops::Range<usize> = 11..18;
}

impl Krang {
    /// The 19×18 actuator matrix `B`: generalized forces `τ = B a` (see the
    /// [module docs](crate::actuators)). Depends on `R` and `L` of the parameter set.
    pub fn actuator_matrix(&self) -> SMatrix<f64, 19, ACTUATOR_COUNT> {
        let (r, l) = (self.params().R, self.params().L);
        let mut b = SMatrix::<f64, 19, ACTUATOR_COUNT>::zeros();
        b[(index::XD, actuator::WHEEL_L)] = 1.0 / r;
        b[(index::XD, actuator::WHEEL_R)] = 1.0 / r;
        b[(index::PSID, actuator::WHEEL_L)] = -l / (2.0 * r);
        b[(index::PSID, actuator::WHEEL_R)] = l / (2.0 * r);
        b[(index::QD_IMU, actuator::WHEEL_L)] = -1.0;
        b[(index::QD_IMU, actuator::WHEEL_R)] = -1.0;
        // Waist, torso and the 14 arm joints: actuator j drives speed j + 1.
        for j in actuator::WAIST..ACTUATOR_COUNT {
            b[(j + 1, j)] = 1.0;
        }
        b
    }

    /// Generalized forces `τ = B a` from the actuator vector
    /// `a = [τ_L, τ_R, τ_waist, τ_torso, τ_1l … τ_7l, τ_1r … τ_7r]` (N·m), ready for
    /// [`Krang::forward_dynamics`]. Cheaper than multiplying by
    /// [`actuator_matrix`](Self::actuator_matrix).
    ///
    /// ```
    /// use krang_dynamics::{Krang, index};
    /// use nalgebra::SVector;
    ///
    /// let k = Krang::default();
    /// let mut a = SVector::<f64, 18>::zeros();
    /// a[0] = 2.0; // τ_L
    /// a[1] = 2.0; // τ_R
    /// let tau = k.generalized_forces(&a);
    /// assert_eq!(tau[index::XD], 4.0 / k.params().R);
    /// assert_eq!(tau[index::PSID], 0.0);
    /// assert_eq!(tau[index::QD_IMU], -4.0);
    /// ```
    pub fn generalized_forces(&self, actuators: &SVector<f64, ACTUATOR_COUNT>) -> SVector<f64, 19> {
        let (r, l) = (self.params().R, self.params().L);
        let (tl, tr) = (actuators[actuator::WHEEL_L], actuators[actuator::WHEEL_R]);
        let mut tau = SVector::<f64, 19>::zeros();
        tau[index::XD] = (tl + tr) / r;
        tau[index::PSID] = l / (2.0 * r) * (tr - tl);
        tau[index::QD_IMU] = -(tl + tr);
        tau.fixed_rows_mut::<16>(index::QD_W)
            .copy_from(&actuators.fixed_rows::<16>(actuator::WAIST));
        tau
    }

    /// Actuator rates `Bᵀ u` (rad/s): for the wheels the rate of each wheel relative to the
    /// base, `θ̇_L − q̇_imu = ẋ/R − (L/2R) ψ̇ − q̇_imu` and `θ̇_R − q̇_imu = ẋ/R + (L/2R) ψ̇ − q̇_imu`
    /// (the gearbox output shaft); for the joints their own speed. The actuator power is
    /// `aᵀ (Bᵀ u) = (B a)ᵀ u`.
    pub fn actuator_velocities(&self, u: &SVector<f64, 19>) -> SVector<f64, ACTUATOR_COUNT> {
        let (r, l) = (self.params().R, self.params().L);
        let mut v = SVector::<f64, ACTUATOR_COUNT>::zeros();
        v[actuator::WHEEL_L] = u[index::XD] / r - l / (2.0 * r) * u[index::PSID] - u[index::QD_IMU];
        v[actuator::WHEEL_R] = u[index::XD] / r + l / (2.0 * r) * u[index::PSID] - u[index::QD_IMU];
        v.fixed_rows_mut::<16>(actuator::WAIST)
            .copy_from(&u.fixed_rows::<16>(index::QD_W));
        v
    }
}

/// Clamps each actuator torque to `±`[`hardware::TORQUE_LIMITS`] (the peak output torques).
/// NaN entries stay NaN.
pub fn saturate(actuators: &SVector<f64, ACTUATOR_COUNT>) -> SVector<f64, ACTUATOR_COUNT> {
    saturate_to(actuators, &hardware::TORQUE_LIMITS)
}

/// Clamps each actuator torque `a[i]` to `[−limits[i], limits[i]]` (e.g. with
/// [`hardware::NOMINAL_TORQUES`] for the continuous ratings). NaN entries stay NaN.
///
/// # Panics
/// If a limit is negative or NaN.
pub fn saturate_to(
    actuators: &SVector<f64, ACTUATOR_COUNT>,
    limits: &[f64; ACTUATOR_COUNT],
) -> SVector<f64, ACTUATOR_COUNT> {
    SVector::from_fn(|i, _| actuators[i].clamp(-limits[i], limits[i]))
}

pub mod hardware {
    //! Motor, gear and limit data of Krang's actuators, from the hardware configuration files
    //! in `krang/hardware/` (`krang_motors.cfg` assigns a drive to each joint; one `.cfg` per
    //! drive type). Each field keeps the name of its key in the file and the file's unit
    //! (stated in each field's documentation); SI conversions are methods. Values marked
    //! "cooked up" are the original authors' own estimates, not datasheet values.
    //!
    //! | actuator | joint (URDF) | drive | peak / nominal torque (N·m) |
    //! |---|---|---|---|
    //! | τ_L, τ_R | JLWheel, JRWheel | [`BLY343D`] + 15:1 gearbox | 63.55 (current limit) / 27.01 (rated) |
    //! | τ_waist | JWaist | [`WAIST`] | 744 / 432 |
    //! | τ_torso | JTorso | [`PRL120`] | 372 / 216 |
    //! | τ_1, τ_2 | LJ1, LJ2, RJ1, RJ2 | [`PRL120`] | 372 / 216 |
    //! | τ_3, τ_4 | LJ3, LJ4, RJ3, RJ4 | [`PRL100`] | 176 / 81.5 |
    //! | τ_5, τ_6 | LJ5, LJ6, RJ5, RJ6 | [`PRL80`] | 41.4 / 20.7 |
    //! | τ_7 | LJFT, RJFT | [`PRL60`] | 9.6 / 4.5 |

    use super::ACTUATOR_COUNT;

    /// One ounce-force inch in N·m (avoirdupois ounce, standard gravity).
    pub const OZ_IN: f64 = 0.45359237 / 16.0 * 9.80665 * 0.0254;
    /// One pound-force inch in N·m.
    pub const LBF_IN: f64 = 0.45359237 * 9.80665 * 0.0254;
    /// One revolution per minute in rad/s.
    pub const RPM: f64 = 2.0 * core::f64::consts::PI / 60.0;

    /// A brushless wheel motor with its planetary gearbox: `bly343d.cfg` (Anaheim
    /// Automation BLY343D-24V-2000 motor, GBPH-0902-NS-015 gearbox; the cfg names the
    /// datasheets). `krang_motors.cfg` lists its make as `amc`.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct WheelDrive {
        /// The model name used in `krang_motors.cfg` (`bly343d`).
        pub model: &'static str,
        /// Motor rated voltage (V).
        pub rated_voltage: f64,
        /// Motor rated speed (RPM).
        pub rated_speed: f64,
        /// Motor rated torque (oz-in, at the motor shaft).
        pub rated_torque: f64,
        /// Motor rated power (W).
        pub rated_power: f64,
        /// Motor rated current (A).
        pub rated_current: f64,
        /// Line-to-line resistance (Ω).
        pub line_to_line_resistance: f64,
        /// Line-to-line inductance (mH).
        pub line_to_line_inductance: f64,
        /// Torque constant (oz-in/A, at the motor shaft).
        pub torque_constant: f64,
        /// Back-EMF constant (V/kRPM).
        pub back_emf_voltage: f64,
        /// Rotor inertia (oz-in-s²).
        pub rotor_inertia: f64,
        /// Gearbox reduction ratio (motor turns per wheel turn).
        pub gear_ratio: f64,
        /// Gearbox rated output torque (lbf-in).
        pub rated_output_torque: f64,
        /// Gearbox maximum output torque (lbf-in).
        pub max_output_torque: f64,
        /// Gearbox rated input speed (RPM).
        pub rated_input_speed: f64,
        /// Number of gearbox stages.
        pub stages: f64,
        /// Gearbox maximum backlash (the cfg states no unit; gearbox backlash is usually
        /// quoted in arc-minutes).
        pub max_backlash: f64,
        /// Maximum motor current (A). Cooked up.
        pub max_input_current: f64,
    }

    impl WheelDrive {
        /// Torque constant at the motor shaft (N·m/A).
        pub const fn torque_constant_si(&self) -> f64 {
            self.torque_constant * OZ_IN
        }

        /// Wheel torque per ampere of motor current, through the gearbox (N·m/A; gearbox
        /// losses neglected).
        pub const fn wheel_torque_per_amp(&self) -> f64 {
            self.torque_constant_si() * self.gear_ratio
        }

        /// Peak wheel torque (N·m): torque constant × maximum current × gear ratio. It is
        /// below the gearbox's maximum output torque, so the current limit is the binding one.
        pub const fn peak_wheel_torque(&self) -> f64 {
            self.wheel_torque_per_amp() * self.max_input_current
        }

        /// Continuous wheel torque (N·m): motor rated torque × gear ratio.
        pub const fn rated_wheel_torque(&self) -> f64 {
            self.rated_torque * OZ_IN * self.gear_ratio
        }

        /// Gearbox maximum output torque (N·m).
        pub const fn max_output_torque_si(&self) -> f64 {
            self.max_output_torque * LBF_IN
        }

        /// Gearbox rated output torque (N·m).
        pub const fn rated_output_torque_si(&self) -> f64 {
            self.rated_output_torque * LBF_IN
        }

        /// Maximum wheel speed (rad/s) at the motor's rated speed.
        pub const fn rated_wheel_speed(&self) -> f64 {
            self.rated_speed * RPM / self.gear_ratio
        }
    }

    /// A Schunk PRL rotary module (`prl60.cfg` … `prl120.cfg`) or the waist drive
    /// (`waist.cfg`): torque at the module output, after its gear.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct JointDrive {
        /// The model name used in `krang_motors.cfg` (`prl120`, `waist`, …).
        pub model: &'static str,
        /// Motor power (W).
        pub motor_power: f64,
        /// Nominal (continuous) output torque (N·m).
        pub nominal_torque: f64,
        /// Peak output torque (N·m).
        pub peak_torque: f64,
        /// Maximum angular velocity (deg/s).
        pub max_angular_velocity: f64,
        /// Maximum angular acceleration (deg/s²).
        pub max_angular_acceleration: f64,
        /// Gear reduction ratio.
        pub gear_ratio: f64,
        /// Current at nominal power (A).
        pub nominal_power_current: f64,
        /// Maximum current (A).
        pub max_current: f64,
        /// Coulomb friction (unit not stated; N·m at the output). Cooked up.
        pub coulomb_friction: f64,
        /// Viscous friction (unit not stated). Cooked up.
        pub viscous_friction: f64,
        /// Position-control PD gains `[P, D]`. Cooked up.
        pub position_ctrl_pd_gains: [f64; 2],
        /// Speed-control PD gains `[P, D]`. Cooked up.
        pub speed_ctrl_pd_gains: [f64; 2],
        /// Reference speed (`waist.cfg` only; unit not stated). Cooked up.
        pub reference_speed: Option<f64>,
    }

    impl JointDrive {
        /// Output torque per ampere at the peak point, `peak_torque / max_current` (N·m/A).
        /// The cfg files give no torque constant; at the nominal point
        /// (`nominal_torque / nominal_power_current`) the ratio differs by up to 16 %.
        pub const fn torque_per_amp(&self) -> f64 {
            self.peak_torque / self.max_current
        }

        /// Maximum angular velocity (rad/s).
        pub const fn max_angular_velocity_si(&self) -> f64 {
            self.max_angular_velocity.to_radians()
        }

        /// Maximum angular acceleration (rad/s²).
        pub const fn max_angular_acceleration_si(&self) -> f64 {
            self.max_angular_acceleration.to_radians()
        }
    }

    /// `bly343d.cfg`: the wheel motors (JLWheel, JRWheel).
    pub const BLY343D: WheelDrive = WheelDrive {
        model: "bly343d",
        rated_voltage: 24.0,
        rated_speed: 2000.0,
        rated_torque: 255.0,
        rated_power: 377.0,
        rated_current: 21.25,
        line_to_line_resistance: 0.09,
        line_to_line_inductance: 0.20,
        torque_constant: 12.0,
        back_emf_voltage: 6.25,
        rotor_inertia: 0.022656,
        gear_ratio: 15.0,
        rated_output_torque: 1487.0,
        max_output_torque: 4461.0,
        rated_input_speed: 3200.0,
        stages: 2.0,
        max_backlash: 16.0,
        max_input_current: 50.0,
    };

    /// `waist.cfg`: the waist drive (JWaist).
    pub const WAIST: JointDrive = JointDrive {
        model: "waist",
        motor_power: 500.0,
        nominal_torque: 432.0,
        peak_torque: 744.0,
        max_angular_velocity: 25.0,
        max_angular_acceleration: 100.0,
        gear_ratio: 596.0,
        nominal_power_current: 10.0,
        max_current: 20.0,
        coulomb_friction: 17.0,
        viscous_friction: 19.0,
        position_ctrl_pd_gains: [5.0, 50.0],
        speed_ctrl_pd_gains: [0.0, 50.0],
        reference_speed: Some(0.5),
    };

    /// `prl120.cfg`: Schunk PRL 120 (JTorso, LJ1, LJ2, RJ1, RJ2).
    pub const PRL120: JointDrive = JointDrive {
        model: "prl120",
        motor_power: 250.0,
        nominal_torque: 216.0,
        peak_torque: 372.0,
        max_angular_velocity: 25.0,
        max_angular_acceleration: 100.0,
        gear_ratio: 596.0,
        nominal_power_current: 5.0,
        max_current: 10.0,
        coulomb_friction: 8.5,
        viscous_friction: 9.8,
        position_ctrl_pd_gains: [300.0, 100.0],
        speed_ctrl_pd_gains: [0.0, 100.0],
        reference_speed: None,
    };

    /// `prl100.cfg`: Schunk PRL 100 (LJ3, LJ4, RJ3, RJ4).
    pub const PRL100: JointDrive = JointDrive {
        model: "prl100",
        motor_power: 130.0,
        nominal_torque: 81.5,
        peak_torque: 176.0,
        max_angular_velocity: 24.0,
        max_angular_acceleration: 95.0,
        gear_ratio: 625.0,
        nominal_power_current: 4.0,
        max_current: 8.0,
        coulomb_friction: 9.0,
        viscous_friction: 10.0,
        position_ctrl_pd_gains: [300.0, 100.0],
        speed_ctrl_pd_gains: [0.0, 100.0],
        reference_speed: None,
    };

    /// `prl80.cfg`: Schunk PRL 80 (LJ5, LJ6, RJ5, RJ6).
    pub const PRL80: JointDrive = JointDrive {
        model: "prl80",
        motor_power: 80.0,
        nominal_torque: 20.7,
        peak_torque: 41.4,
        max_angular_velocity: 25.0,
        max_angular_acceleration: 100.0,
        gear_ratio: 552.0,
        nominal_power_current: 3.0,
        max_current: 6.0,
        coulomb_friction: 3.2,
        viscous_friction: 3.4,
        position_ctrl_pd_gains: [30.0, 10.0],
        speed_ctrl_pd_gains: [0.0, 10.0],
        reference_speed: None,
    };

    /// `prl60.cfg`: Schunk PRL 60 (LJFT, RJFT, the wrist rotation q7).
    pub const PRL60: JointDrive = JointDrive {
        model: "prl60",
        motor_power: 40.0,
        nominal_torque: 4.5,
        peak_torque: 9.6,
        max_angular_velocity: 50.0,
        max_angular_acceleration: 200.0,
        gear_ratio: 300.0,
        nominal_power_current: 2.0,
        max_current: 4.0,
        coulomb_friction: 3.5,
        viscous_friction: 3.7,
        position_ctrl_pd_gains: [30.0, 10.0],
        speed_ctrl_pd_gains: [0.0, 10.0],
        reference_speed: None,
    };

    /// The drive behind one actuator.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub enum Drive {
        /// A wheel motor with gearbox.
        Wheel(WheelDrive),
        /// A Schunk module or the waist drive.
        Joint(JointDrive),
    }

    impl Drive {
        /// The model name (`bly343d`, `waist`, `prl120`, …).
        pub const fn model(&self) -> &'static str {
            match self {
                Drive::Wheel(w) => w.model,
                Drive::Joint(j) => j.model,
            }
        }

        /// Peak output torque (N·m).
        pub const fn peak_torque(&self) -> f64 {
            match self {
                Drive::Wheel(w) => w.peak_wheel_torque(),
                Drive::Joint(j) => j.peak_torque,
            }
        }

        /// Continuous (rated / nominal) output torque (N·m).
        pub const fn nominal_torque(&self) -> f64 {
            match self {
                Drive::Wheel(w) => w.rated_wheel_torque(),
                Drive::Joint(j) => j.nominal_torque,
            }
        }
    }

    /// One actuator: its joint in the URDF and `krang_motors.cfg`, and its drive.
    #[derive(Clone, Copy, Debug, PartialEq)]
    pub struct Actuator {
        /// Joint name in `krang_motors.cfg` and `Krang.urdf` (`JLWheel`, `LJ1`, `LJFT`, …).
        pub joint: &'static str,
        /// `<joint>_make` in `krang_motors.cfg` (`amc`, `waist`, `schunk`).
        pub make: &'static str,
        /// The drive (`<joint>_model` in `krang_motors.cfg`).
        pub drive: Drive,
    }

    const fn schunk(joint: &'static str, drive: JointDrive) -> Actuator {
        Actuator {
            joint,
            make: "schunk",
            drive: Drive::Joint(drive),
        }
    }

    /// The 18 actuators in the order of the actuator vector (`krang_motors.cfg`).
    pub const ACTUATORS: [Actuator; ACTUATOR_COUNT] = [
        Actuator {
            joint: "JLWheel",
            make: "amc",
            drive: Drive::Wheel(BLY343D),
        },
        Actuator {
            joint: "JRWheel",
            make: "amc",
            drive: Drive::Wheel(BLY343D),
        },
        Actuator {
            joint: "JWaist",
            make: "waist",
            drive: Drive::Joint(WAIST),
        },
        schunk("JTorso", PRL120),
        schunk("LJ1", PRL120),
        schunk("LJ2", PRL120),
        schunk("LJ3", PRL100),
        schunk("LJ4", PRL100),
        schunk("LJ5", PRL80),
        schunk("LJ6", PRL80),
        schunk("LJFT", PRL60),
        schunk("RJ1", PRL120),
        schunk("RJ2", PRL120),
        schunk("RJ3", PRL100),
        schunk("RJ4", PRL100),
        schunk("RJ5", PRL80),
        schunk("RJ6", PRL80),
        schunk("RJFT", PRL60),
    ];

    const fn peak_torques() -> [f64; ACTUATOR_COUNT] {
        let mut t = [0.0; ACTUATOR_COUNT];
        let mut i = 0;
        while i < ACTUATOR_COUNT {
            t[i] = ACTUATORS[i].drive.peak_torque();
            i += 1;
        }
        t
    }

    const fn nominal_torques() -> [f64; ACTUATOR_COUNT] {
        let mut t = [0.0; ACTUATOR_COUNT];
        let mut i = 0;
        while i < ACTUATOR_COUNT {
            t[i] = ACTUATORS[i].drive.nominal_torque();
            i += 1;
        }
        t
    }

    /// Peak output torque of each actuator (N·m), the limits of [`saturate`](super::saturate):
    /// `peak_torque` of the Schunk/waist cfg files; for the wheels
    /// `torque_constant × max_input_current × gear_ratio` = 63.55 N·m.
    pub const TORQUE_LIMITS: [f64; ACTUATOR_COUNT] = peak_torques();

    /// Continuous output torque of each actuator (N·m): `nominal_torque` of the Schunk/waist
    /// cfg files; for the wheels `rated_torque × gear_ratio` = 27.01 N·m.
    pub const NOMINAL_TORQUES: [f64; ACTUATOR_COUNT] = nominal_torques();
}
