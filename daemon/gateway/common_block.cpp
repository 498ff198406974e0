#include "gateway/common_block.h"

#include <string>

namespace drivegate {

PointSpec common_spec(const CommonRow& row) {
  PointSpec p = make_point(row.table, row.type, row.name, row.unit, row.description);
  p.limited(row.min, row.max);
  switch (row.labels) {
    case CommonLabels::none:
      break;
    case CommonLabels::status_bits:
      p.named_bits(labels_in_order(kStatusBitNames));
      break;
    case CommonLabels::faults:
      p.named_values(labels_in_order(kFaultNames));
      break;
    case CommonLabels::fault_bits:
      p.named_bits(labels_in_order(kFaultNames));
      break;
    case CommonLabels::commands:
      p.named_values(labels_in_order(kCommandNames));
      break;
  }
  return p;
}

PointSpec status_bit_spec(std::size_t bit) {
  return make_point(Table::discrete, PointType::u16,
                    "status_" + std::string(kStatusBitNames.at(bit)), "",
                    "status bit " + std::to_string(bit));
}

}  // namespace drivegate
