#include "points.h"

#include <array>
#include <string_view>

#include "faults.h"

namespace drivegate::mdriver {

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> v(pt::count);
  // Section 3 No.2, reply R4..R11.
  v[pt::target_code] =
      input_point("target_code", PointType::u16, "", "R4: target frequency code the driver echoes");
  v[pt::target_rpm] =
      input_point("target_rpm", PointType::u16, "rpm", "R4 through the code -> rpm table");
  v[pt::actual_code] =
      input_point("actual_code", PointType::u16, "", "R5: actual running frequency code");
  v[pt::error_code] =
      input_point("error_code", PointType::u16, "", "R7: driver error code (0 = no error)")
          .named_values(error_code_labels());
  v[pt::ipm_temperature] =
      input_point("ipm_temperature", PointType::u16, "degC", "R8: IPM sensor temperature")
          .trended();
  v[pt::info_1] =
      input_point("info_1", PointType::u16, "", "R9: information 1 (raw, 00 in the document)");
  v[pt::info_2] =
      input_point("info_2", PointType::u16, "", "R10: information 2 (raw, 00 in the document)");
  v[pt::info_3] =
      input_point("info_3", PointType::u16, "", "R11: information 3 (raw, 00 in the document)");
  v[pt::sent_code] = input_point("sent_code", PointType::u16, "",
                                 "D4 the gateway last sent (target frequency code)");
  constexpr std::array<std::string_view, 3> kFixedCodeStates = {"unchecked", "ok",
                                                                "fixed_code_error"};
  v[pt::fixed_code_state] = input_point("fixed_code_state", PointType::u16, "",
                                        "fixed-code check (command 00): 0 unchecked, 1 ok, 2 error")
                                .named_values(labels_in_order(kFixedCodeStates));
  return v;
}

}  // namespace drivegate::mdriver
