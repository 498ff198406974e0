#include <string>

#include "driver.h"
#include "error_codes.h"

namespace drivegate::mdriver {
namespace {

PointSpec input(std::string name, std::string unit, std::string description) {
  PointSpec p;
  p.name = std::move(name);
  p.table = Table::input;
  p.type = PointType::u16;
  p.unit = std::move(unit);
  p.description = std::move(description);
  return p;
}

}  // namespace

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> v(static_cast<std::size_t>(Pt::count));
  auto at = [&v](Pt p) -> PointSpec& { return v[static_cast<std::size_t>(p)]; };
  // Section 3 No.2, reply R4..R11.
  at(Pt::target_code) = input("target_code", "", "R4: target frequency code the driver echoes");
  at(Pt::target_rpm) = input("target_rpm", "rpm", "R4 through the code -> rpm table");
  at(Pt::actual_code) = input("actual_code", "", "R5: actual running frequency code");
  at(Pt::error_code) = input("error_code", "", "R7: driver error code (0 = no error)");
  at(Pt::error_code).labels.push_back({"none", 0});
  for (const auto& e : error_codes()) {
    at(Pt::error_code).labels.push_back({std::string(e.name), e.code});
  }
  at(Pt::ipm_temperature) = input("ipm_temperature", "degC", "R8: IPM sensor temperature");
  at(Pt::info_1) = input("info_1", "", "R9: information 1 (raw, 00 in the document)");
  at(Pt::info_2) = input("info_2", "", "R10: information 2 (raw, 00 in the document)");
  at(Pt::info_3) = input("info_3", "", "R11: information 3 (raw, 00 in the document)");
  at(Pt::sent_code) = input("sent_code", "", "D4 the gateway last sent (target frequency code)");
  at(Pt::fixed_code_state) =
      input("fixed_code_state", "", "fixed-code check (command 00): 0 unchecked, 1 ok, 2 error");
  at(Pt::fixed_code_state).labels = {{"unchecked", 0}, {"ok", 1}, {"fixed_code_error", 2}};
  return v;
}

}  // namespace drivegate::mdriver
