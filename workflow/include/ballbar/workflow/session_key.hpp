// SPDX-License-Identifier: MIT
#pragma once

#include <string_view>

namespace ballbar::workflow {

/// True when `arg` can only be a session key (an id or a uuid prefix: digits and hex letters), so a use
/// case taking "FILE or SESSION" can say "no such file" for anything else that is not a file.
bool looks_like_session_key(std::string_view arg);

}  // namespace ballbar::workflow
