// SPDX-License-Identifier: MIT
// The page's files, compiled in (webui/page/, embedded by webui/embed.cmake at build time): the server
// serves these and nothing else.
#pragma once

#include <span>
#include <string_view>

namespace ballbar::webui {

struct Asset {
    std::string_view path;  ///< "/index.html", "/app.js", …
    std::string_view content_type;
    std::string_view body;
};

std::span<const Asset> assets();

}  // namespace ballbar::webui
