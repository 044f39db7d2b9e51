#pragma once
/// Homing: waiting, with zero motor words and the red LED, until all three motors report
/// homed (the user pulls the grip out and pushes it in), then the green LED.

#include "FalconIoThread.h"

#include <chrono>
#include <string>

namespace hapto::falcon {

/// Holds `io`'s motor words at zero and polls its newest sample until the homed flags are all
/// set (true, LED green) or `timeout` passes or the I/O thread stops running (false, `error`
/// says what to do). Prompts on stderr after 0.5 s. `deviceName` names the device in
/// messages. [control]
bool homeFalcon(FalconIoThread& io, const std::string& deviceName,
                std::chrono::milliseconds timeout, std::string& error);

} // namespace hapto::falcon
