#include "kg/graph/value.hpp"

namespace kg::graph {

namespace {

// Members are destroyed in reverse order: the data (whose destructor may be code in the owner's
// library) goes before the owner.
struct OwnedData {
  std::shared_ptr<const void> owner;
  std::shared_ptr<const void> data;
};

}  // namespace

Value Value::kept_alive_by(std::shared_ptr<const void> owner) const {
  if (!owner || !data_) return *this;
  auto holder = std::make_shared<const OwnedData>(OwnedData{std::move(owner), data_});
  Value v;
  v.type_ = type_;
  v.data_ = std::shared_ptr<const void>(holder, holder->data.get());
  return v;
}

void Value::throw_type_mismatch(const char* wanted) const {
  if (!data_) throw Error(std::string("expected a value of type ") + wanted + ", got none (empty value)");
  throw Error(std::string("expected a value of type ") + wanted + ", got " + type_);
}

}  // namespace kg::graph
