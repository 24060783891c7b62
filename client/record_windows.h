// A record set from the command line: a folder or a CSV, and for one CSV the windows given by
// --train-window / --validate-window / --test-window (START:END in seconds, repeatable).
#pragma once

#include <string>
#include <vector>

#include "io/records.h"

namespace pz::client {

io::RecordSet LoadRecordSetWithWindows(const std::string& path, const std::vector<std::string>& train,
                                       const std::vector<std::string>& validate, const std::vector<std::string>& test);

}  // namespace pz::client
