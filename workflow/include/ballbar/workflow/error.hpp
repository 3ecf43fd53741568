// SPDX-License-Identifier: MIT
// What went wrong, in the categories every front end answers the same way: the CLI maps them to its exit
// codes (one table, app/command.hpp), a web page to HTTP statuses, a controller module to a refusal.
// The libraries keep their own error types (StorageError, FileError, DeviceError, …); category_of sorts
// every one of them, so no front end maps library errors one by one.
#pragma once

#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ballbar::workflow {

enum class ErrorCategory {
    bad_input,    ///< the user's input cannot be used: an option, a file's content, a request
    not_found,    ///< a session, model, file or device the user named does not exist
    device,       ///< the instrument or its link failed: not there, not answering, unfit, lost
    failed,       ///< valid input, but the operation could not succeed: not converged, refused by quality
                  ///< checks, a database or disk that failed
    interrupted,  ///< stopped by the operator or a signal; what was measured is kept and can be resumed
    internal,     ///< a bug: an error nobody expected
};

/// "bad input", "not found", "device", "failed", "interrupted", "internal".
std::string_view to_string(ErrorCategory category);

/// An error of the workflow layer (and of the front ends above it): the message says what and why in
/// the user's terms, the category how a front end answers.
class Error : public std::runtime_error {
  public:
    Error(ErrorCategory category, const std::string& message) : std::runtime_error(message), category_(category) {}
    ErrorCategory category() const { return category_; }

  private:
    ErrorCategory category_;
};

/// The category of any error a library of ballbar throws (and of std::bad_alloc: failed); an exception
/// of a type nobody sorted is `internal`.
ErrorCategory category_of(const std::exception& e);

}  // namespace ballbar::workflow
