#include "qs/core/context.h"

#include "qs/core/error.h"

namespace qs {

void Context::check_cancel() const {
  if (cancel && cancel->load()) throw Error(ErrorCode::Internal, "cancelled");
}

}  // namespace qs
