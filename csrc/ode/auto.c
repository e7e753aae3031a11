/* The switching row "auto": dop853 while the problem is not stiff, radau
 * while it is, as the driver's stiffness tests decide (driver.c,
 * switch_method).  A row of two existing methods: no step of its own. */
#include "ode/ode.h"

extern const mp_ode_method mp_ode_dop853, mp_ode_radau;

const mp_ode_method mp_ode_auto = {
    .name = "auto", .order = 8, .adaptive = 1, .implicit = 1, .needs_jacobian = 1,
    .dense_order = 3, .ncoef = 8, .nscratch = 15,
    .nonstiff = &mp_ode_dop853, .stiff = &mp_ode_radau,
};
