// The dashboard's page and scripts, embedded in the binary at build time (client/CMakeLists.txt):
// dashboard/page/*.{html,js} of this project, and Debian's Chart.js (libjs-chart.js) and marked
// (libjs-marked). Nothing is fetched at run time.
#pragma once

#include <string_view>

namespace pz::dashboard::assets {
extern const std::string_view kIndexHtml;
extern const std::string_view kReportHtml;
extern const std::string_view kDashboardJs;
extern const std::string_view kChartJs;
extern const std::string_view kMarkedJs;
}  // namespace pz::dashboard::assets
