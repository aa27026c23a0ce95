// A type-erased, immutable, shareable value travelling on a port, tagged with a stable type name.
// Type identity across shared libraries is the name string, never typeid (DESIGN.md 4).
//
//   KG_DECLARE_TYPE(kg::motion::Motion, "kg.Motion")      // once, in the header declaring Motion
//   Value v = Value::make(motion);                        // copies or moves motion into shared storage
//   const Motion& m = v.get<Motion>();                    // throws Error when v holds another type
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "kg/base/error.hpp"
#include "kg/base/report.hpp"

namespace kg::graph {

// Specialise through KG_DECLARE_TYPE; the name is the port type users see ("kg.Motion").
template <class T>
struct TypeName;

#define KG_DECLARE_TYPE(CppType, Name)         \
  template <>                                  \
  struct kg::graph::TypeName<CppType> {        \
    static constexpr const char* value = Name; \
  };

template <class T>
concept Named = requires {
  TypeName<T>::value;
};

class Value {
 public:
  Value() = default;

  template <Named T>
  static Value make(T value) {
    Value v;
    v.type_ = TypeName<T>::value;
    v.data_ = std::make_shared<const T>(std::move(value));
    return v;
  }

  // Shares existing storage without a copy.
  template <Named T>
  static Value share(std::shared_ptr<const T> data) {
    Value v;
    v.type_ = TypeName<T>::value;
    v.data_ = std::move(data);
    return v;
  }

  bool empty() const { return !data_; }
  const std::string& type_name() const { return type_; }

  template <Named T>
  bool holds() const {
    return data_ && type_ == TypeName<T>::value;
  }

  template <Named T>
  const T& get() const {
    if (!holds<T>()) throw_type_mismatch(TypeName<T>::value);
    return *static_cast<const T*>(data_.get());
  }

  template <Named T>
  std::shared_ptr<const T> get_shared() const {
    if (!holds<T>()) throw_type_mismatch(TypeName<T>::value);
    return std::static_pointer_cast<const T>(data_);
  }

  // The same value, whose storage also keeps `owner` alive (a plugin's library: the value's
  // destructor code lives there). The value's data is released before the owner.
  Value kept_alive_by(std::shared_ptr<const void> owner) const;

 private:
  [[noreturn]] void throw_type_mismatch(const char* wanted) const;

  std::string type_;
  std::shared_ptr<const void> data_;
};

}  // namespace kg::graph

// Plain types every graph may use on ports.
KG_DECLARE_TYPE(double, "kg.Scalar")
KG_DECLARE_TYPE(std::int64_t, "kg.Int")
KG_DECLARE_TYPE(bool, "kg.Bool")
KG_DECLARE_TYPE(std::string, "kg.String")
// A JSON document (kg/base/report.hpp): a solver's report, written by a sink (io.write_report).
KG_DECLARE_TYPE(kg::Report, "kg.Report")
