#pragma once
/// The report page's files (apps/report/), embedded in the binary at build time
/// (cmake/NbvEmbed.cmake), so that an installed nbv writes pages without its source tree.

#include <string_view>

namespace nbv::apps::report_files {

/// page.html: the page, with {{name}} where writeReportHtml() puts the title, style, scripts
/// and data.
extern const std::string_view kPageHtml;
/// page.js: the script that draws NBV_DATA.
extern const std::string_view kPageJs;
/// page.css: the page's style.
extern const std::string_view kPageCss;

}  // namespace nbv::apps::report_files
