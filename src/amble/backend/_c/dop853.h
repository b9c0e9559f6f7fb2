/* The state of the DOP853 integrator (dop853_step.h) and its stepper (stepper.h). Shared by the
 * model's unit, which compiles the step and defines dop853_stepper, and the runtime (runtime.c),
 * compiled once per capacity: the arrays hold AMBLE_NXCAP entries (the model's NXMAX rounded up
 * to a capacity bucket, backend/runtime.py), the same in both units.
 *
 * Needs from the including unit: AMBLE_NXCAP, AMBLE_HIDDEN (amble_core.h).
 */
#ifndef AMBLE_DOP853_H
#define AMBLE_DOP853_H
#include "stepper.h"
#include "dop853_tableau.h"

typedef struct {
    Step b; /* first: a Dop is reached from its Step */
    double K[DOP_STAGES_EXT][AMBLE_NXCAP];
    double F[DOP_INTERP][AMBLE_NXCAP];
    int dense_ready;
} Dop;

/* DOP853 in the model's unit (dop853_step.h): its step, with the right-hand side inlined */
extern AMBLE_HIDDEN const Stepper dop853_stepper;

#endif
