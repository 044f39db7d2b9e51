#pragma once
/// The error for bad input from people: files, device data, command-line arguments.

#include <stdexcept>
#include <string>

namespace hapto {

/// Bad input: the message says what is wrong and where (file, JSON path, line), and what to do.
/// Thrown only on control threads; the `hapto` command turns it into exit code 2.
class InputError : public std::runtime_error {
public:
    /// `message` is the whole text shown to the user: what, where and what to do.
    explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

} // namespace hapto
