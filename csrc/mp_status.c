#include "mp_status.h"

const char *mp_status_message(int status)
{
    switch (status) {
    case MP_OK: return "success";
    case MP_EDOM: return "argument out of domain";
    case MP_ENOMEM: return "out of memory";
    case MP_EMAXSTEPS: return "the step budget (max_steps) was exhausted";
    case MP_ESTEP: return "the step size fell below round-off";
    case MP_ENOTSPD: return "matrix is not symmetric positive definite";
    case MP_ECALLBACK: return "a callback failed";
    case MP_EINTR: return "interrupted";
    case MP_ENONFINITE: return "a non-finite value (NaN or inf) was produced";
    case MP_ENOCONV: return "the iteration did not converge";
    case MP_ESINGULAR: return "singular configuration";
    case MP_EMESH: return "invalid mesh";
    case MP_EGSL: return "GSL reported an error";
    case MP_EUNSTABLE: return "the system is unstable";
    default: return "unknown status";
    }
}
