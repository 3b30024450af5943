//! After `KinDyn::new`, neither `set_state` nor any computation (the inertial-parameter regressors included)
//! allocates (counting global allocator).

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Vector6};
use stride_model::{ExternalWrench, KinDyn, Model, VelocityRepresentation};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

fn exercise(model: Arc<Model>) {
    let nv = model.nv();
    let n = model.dof();
    let states: Vec<_> = (0..3).map(|k| common::random_state(&model, k)).collect();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let frames: Vec<_> = model
        .frames()
        .iter()
        .map(|f| model.frame_id(&f.name).unwrap())
        .collect();
    let mut jac = DMatrix::zeros(6, nv);
    let mut jcom = DMatrix::zeros(3, nv);
    let mut cmm = DMatrix::zeros(6, nv);
    let mut mass = DMatrix::zeros(nv, nv);
    let mut vec_nv = DVector::zeros(nv);
    let mut acc = DVector::zeros(nv);
    let nu_dot = common::random_vector(nv, 5, 1.0);
    let tau = common::random_vector(n, 6, 10.0);
    let wrenches = [ExternalWrench {
        frame: frames[frames.len() - 1],
        wrench: Vector6::new(1.0, 2.0, 3.0, 0.1, 0.2, 0.3),
    }];
    let mut integrated = states[0].clone();
    let mut ft = vec![Vector6::zeros(); model.ft_sensors().len()];
    let mut ft_map = nalgebra::Matrix6::zeros();
    let ns = model.ft_sensors().len();
    let mut y_full = DMatrix::zeros(nv, 10 * model.body_count());
    let mut y_ft = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut y_sub = DMatrix::zeros(6, 10 * (model.body_count() + ns));
    let cut: Vec<usize> = (0..ns).collect();

    let mut sink = 0.0;
    // only this thread's allocations count (the test harness may allocate on its own threads)
    let (_, allocations) = ALLOC.allocations_during(|| {
        for rep in [
            VelocityRepresentation::Mixed,
            VelocityRepresentation::Body,
            VelocityRepresentation::Inertial,
        ] {
            kd.set_representation(rep);
            for state in &states {
                kd.set_state(state).unwrap();
                for &f in &frames {
                    sink += kd.frame_pose(f).translation.vector.x;
                    sink += kd.relative_transform(frames[0], f).translation.vector.y;
                    sink += kd.frame_velocity(f)[0];
                    sink += kd.frame_bias_acceleration(f)[3];
                    kd.frame_jacobian(f, &mut jac).unwrap();
                }
                sink += kd.com_position().x + kd.com_velocity().y + kd.com_bias_acceleration().z;
                kd.com_jacobian(&mut jcom).unwrap();
                sink += kd.centroidal_momentum()[4] + kd.centroidal_momentum_bias()[5];
                kd.centroidal_momentum_matrix(&mut cmm).unwrap();
                kd.mass_matrix(&mut mass).unwrap();
                kd.mass_matrix_lower(|r, c, v| sink += v * (r + c) as f64);
                kd.bias_forces(&mut vec_nv).unwrap();
                kd.ft_sensor_wrenches(&nu_dot, &wrenches, &mut ft).unwrap();
                for (s, reading) in ft.iter().enumerate() {
                    kd.ft_sensor_wrench_map(s, frames[0], &mut ft_map).unwrap();
                    sink += reading[2] + ft_map[(0, 0)];
                }
                kd.ft_sensor_readings(&nu_dot, &wrenches, &mut ft).unwrap();
                kd.ft_sensor_wrenches(&nu_dot, &[], &mut ft).unwrap();
                kd.inverse_dynamics_after_ft_sensors(&wrenches, &mut vec_nv)
                    .unwrap();
                kd.gravity_forces(&mut vec_nv).unwrap();
                kd.inverse_dynamics(&nu_dot, &wrenches, &mut vec_nv)
                    .unwrap();
                kd.forward_dynamics(&tau, &wrenches, &mut acc).unwrap();
                kd.inverse_dynamics_regressor(&nu_dot, &mut y_full).unwrap();
                kd.ft_sensor_regressor(&nu_dot, &mut y_ft).unwrap();
                kd.ft_submodel_base_regressor(&nu_dot, &cut, &mut y_sub)
                    .unwrap();
                for k in 0..ns {
                    kd.ft_sensor_parent_side_map(k, &mut ft_map).unwrap();
                    sink += ft_map[(0, 0)];
                }
                sink += y_full[(6, 10)] + y_ft[(0, 0)] + y_sub[(2, 0)];
                kd.state_into(&mut integrated);
                integrated.integrate(&model, rep, 1e-3).unwrap();
            }
        }
    });
    assert!(sink.is_finite());
    assert_eq!(
        allocations, 0,
        "{allocations} allocations after KinDyn::new"
    );
}

#[test]
fn no_allocation_after_new() {
    exercise(common::test_model());
    exercise(common::humanoid_model().expect("models/stride_humanoid.urdf must exist"));
}
