// Typed extension points (DESIGN.md 5, 14): objects of an interface graph/ does not know (a
// constraint kind, a motion file format, ...) registered by name, built-in or from a plugin. An
// interface declares its stable name once, next to its port types, and every lookup is typed:
//
//   KG_DECLARE_INTERFACE(kg::retarget::ConstraintKind, "kg.ConstraintKind")   // once, in an adapter header
//   record.add_extension<ConstraintKind>("ladder.rung", make_rung_kind(), "a rung");   // a plugin
//   std::shared_ptr<const ConstraintKind> kind = registry.find<ConstraintKind>("ladder.rung");
//   std::shared_ptr<const ConstraintKind> same = ctx.find<ConstraintKind>("ladder.rung");  // a node
//
// Type identity across shared libraries is the interface's name string, never typeid (as for
// port types, value.hpp). The object is stored as the std::shared_ptr<const T> it was made from,
// so the one cast back to T, in Registry::find and RunContext::find, is exact.
#pragma once

#include <memory>
#include <string>
#include <type_traits>
#include <utility>

namespace kg::graph {

// Specialise through KG_DECLARE_INTERFACE; the name is what messages and plugins see.
template <class T>
struct InterfaceName;

#define KG_DECLARE_INTERFACE(CppType, Name)    \
  template <>                                  \
  struct kg::graph::InterfaceName<CppType> {   \
    static constexpr const char* value = Name; \
  };

template <class T>
concept Interface = requires {
  InterfaceName<T>::value;
};

class Registry;

// One named object of a declared interface, as a plugin record lists it and the registry stores
// it. Immutable; made only by make<T>, so the interface name always matches the object.
class Extension {
 public:
  Extension() = default;

  // `object` may point to a class derived from T (it is converted to T first). Null is allowed
  // here and refused when registered ("has no factory").
  template <Interface T>
  static Extension make(std::string name, std::type_identity_t<std::shared_ptr<const T>> object,
                        std::string doc = {}) {
    Extension e;
    e.interface_ = InterfaceName<T>::value;
    e.name_ = std::move(name);
    e.doc_ = std::move(doc);
    e.object_ = std::move(object);
    return e;
  }

  const std::string& interface() const { return interface_; }  // e.g. "kg.ConstraintKind"
  const std::string& name() const { return name_; }            // e.g. "ladder.rung"
  const std::string& doc() const { return doc_; }
  bool empty() const { return !object_; }

  // The object as a T; null when empty or of another interface.
  template <Interface T>
  std::shared_ptr<const T> get() const {
    if (!object_ || interface_ != InterfaceName<T>::value) return nullptr;
    return std::static_pointer_cast<const T>(object_);
  }

  // The same extension, whose object also keeps `owner` alive (a plugin's library: the object's
  // destructor code lives there). The object is released before the owner.
  Extension kept_alive_by(std::shared_ptr<const void> owner) const;

 private:
  friend class Registry;  // stores and hands out the type-erased object

  std::string interface_;
  std::string name_;
  std::string doc_;
  std::shared_ptr<const void> object_;
};

}  // namespace kg::graph
