#pragma once
#include "common.h"

namespace rvlio::python {
void BindEval(py::module_& m);
}  // namespace rvlio::python
