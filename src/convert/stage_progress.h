// Progress and cancellation of the conversion's long stages (thesis 6): each stage calls its StageProgress
// now and then with the fraction done; a callback that returns false cancels the conversion, which then
// throws ConversionCancelled from that stage.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace rc {

/// Fraction done in [0, 1]; return false to cancel.
using StageProgress = std::function<bool(double fraction)>;

struct ConversionCancelled : std::runtime_error {
  explicit ConversionCancelled(const std::string& stage) : std::runtime_error("cancelled during " + stage) {}
};

}  // namespace rc
