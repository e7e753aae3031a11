/* Rigid bodies: the C entry points shared by the scene models, the geometric
 * method row (ode/rigid_split.c) and the binding. */
#ifndef MP_RIGID_H
#define MP_RIGID_H

#include <stddef.h>

#include "models/models.h"

/* MP_EDOM unless the three moments are finite, positive and satisfy the
 * triangle inequality I_i <= I_j + I_k. */
int mp_rigid_check_moments(const double *mom);

/* The RigidBody right-hand sides; data = (I1, I2, I3, tau1, tau2, tau3). */
int mp_rigid_rhs_free(double t, const double *y, double *f, void *d);
int mp_rigid_rhs_torque(double t, const double *y, double *f, void *d);
int mp_rigid_rhs_free_q(double t, const double *y, double *f, void *d);
int mp_rigid_rhs_torque_q(double t, const double *y, double *f, void *d);

/* A body-frame torque given as a C function of the scene state y (omega, and
 * the quaternion with orientation): tau[0..2] = torque(t, y). */
typedef void (*mp_rigid_torque_fn)(double t, const double *y, double *tau, void *user_data);
typedef struct mp_rigid_torque {
    const double *params; /* the model's parameters (I1, I2, I3, ...) */
    mp_rigid_torque_fn fn;
    void *user_data;
} mp_rigid_torque;

/* Bind model m (RigidBody or RigidBodyOriented, parameters already checked)
 * with the torque callback tq, which must outlive prob; no analytic Jacobian
 * (the torque's derivative is unknown).  MP_EDOM when m is another model. */
int mp_rigid_bind_torque(const mp_model *m, const mp_rigid_torque *tq, mp_ode_problem *prob);

/* 1: a RigidBody problem (omega), 2: with the quaternion, 0: something else
 * (a torque callback included: the split methods need a constant torque). */
int mp_rigid_is_body(const mp_ode_problem *p);

/* The exact torque-free body angular velocity at nt times into out (nt x 3). */
int mp_rigid_free_rotation(const double *mom, const double *w0, const double *t, size_t nt,
                           double *out);
/* The period of omega(t) of the free motion (two intermediate-axis flips). */
int mp_rigid_flip_period(const double *mom, const double *w0, double *T);

#endif
