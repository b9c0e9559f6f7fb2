/* The model-independent runtime: the hybrid simulation loop (hybrid.c and the headers it
 * includes), compiled once per capacity bucket, compiler and flags into an object in the cache
 * (backend/runtime.py) and linked into every model's library. The model's sizes, tables and
 * kernels are hidden symbols of the model's unit (model.h, model_tail.h).
 *
 * Compiled with -DAMBLE_NXCAP=<capacity> and amble_abi.h (the interface codes of
 * amble/backend/abi.py) on the include path.
 */
#include "amble_core.h"
#include "amble_abi.h"
#include "model.h"
#include "hybrid.c"
