//! What `toolconf simulate --arm M1,M2,L1,L2 --task T --method explicit` prints for the tools
//! and tasks the host tests run: `task_error` of `--json`, and θ1, θ2, θ̇1, θ̇2 of the last row
//! (t = 5 s) of `--csv`, at ode45's default tolerances and at `--rtol 1e-10 --atol 1e-12`.
//! The workspace's `tests/on_robot_reference.rs` runs those commands and checks that these are
//! still their output, digit for digit.

/// One reference episode.
pub struct Reference {
    pub arm: [f64; 4],
    pub task: &'static str,
    pub task_error: f64,
    pub last: [f64; 4],
    pub tight_task_error: f64,
    pub tight_last: [f64; 4],
}

pub const REFERENCES: [Reference; 2] = [
    Reference {
        arm: [0.3, 0.4, 0.5, 0.2],
        task: "position",
        task_error: 13612.258208107896,
        last: [
            0.8827925096034315,
            0.49542173206272666,
            0.06934528046121358,
            0.01181919571115095,
        ],
        tight_task_error: 13612.257576010981,
        tight_last: [
            0.8827925093688364,
            0.4954217419824358,
            0.06934547191075888,
            0.0118182307129015,
        ],
    },
    Reference {
        arm: [0.3, 0.4, 0.5, 0.2],
        task: "velocity",
        task_error: 208.1881307242599,
        last: [
            -1.5721102466270005,
            8.412690684035406,
            0.03403796313581918,
            2.011835202567206,
        ],
        tight_task_error: 208.18691380507212,
        tight_last: [
            -1.5721102476434996,
            8.412690700405076,
            0.03403949666141764,
            2.0118509524987167,
        ],
    },
];
