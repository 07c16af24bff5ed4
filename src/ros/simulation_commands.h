// The start / pause / step / frame / reset protocol (SimulationCommand.srv) shared by the simulator nodes:
// the node says what each command does, the dispatcher parses the request and refuses unknown commands.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "relaxed_connectivity/SimulationCommand.h"

namespace rc {

struct CommandResult {
  bool success = true;
  std::string message;
};

struct SimulationCommandHandlers {
  std::function<CommandResult()> start, pause, reset;
  std::function<CommandResult(uint32_t steps)> step;    ///< solver steps >= 1 (a request of 0 is 1)
  std::function<CommandResult(uint32_t frames)> frame;  ///< frames >= 1 (a request of 0 is 1)
};

/// Runs the handler of request.command; an unknown command fails naming the known ones.
inline void dispatchSimulationCommand(const relaxed_connectivity::SimulationCommand::Request& request,
                                      relaxed_connectivity::SimulationCommand::Response& response,
                                      const SimulationCommandHandlers& handlers) {
  CommandResult result;
  if (request.command == "start") {
    result = handlers.start();
  } else if (request.command == "pause") {
    result = handlers.pause();
  } else if (request.command == "step") {
    result = handlers.step(request.steps > 0 ? request.steps : 1);
  } else if (request.command == "frame") {
    result = handlers.frame(request.steps > 0 ? request.steps : 1);
  } else if (request.command == "reset") {
    result = handlers.reset();
  } else {
    result = {false, "unknown command '" + request.command + "' (start, pause, step, frame, reset)"};
  }
  response.success = result.success;
  response.message = result.message;
}

}  // namespace rc
