#pragma once
/// The page's own files, built into the library from view/assets/ (ViewAssets.cpp.in).

namespace hapto::view_assets {

/// view/assets/index.html.
extern const char* const kIndexHtml;
/// view/assets/view.js.
extern const char* const kViewJs;

} // namespace hapto::view_assets
