#pragma once
// The registry behind both open interfaces of the grid (angular binnings, depth binnings): factories by tag,
// the built-ins from the start, thread-safe. Private to the library.
#include "occ_improve/errors.hpp"

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace occ_improve {

struct GeometryParams;

namespace detail {

constexpr std::size_t kMaxTagLength = 64;  // the map format's limit too (docs/MAP_FORMAT.md)

template <typename Product>
class TagRegistry {
public:
  using Factory = std::function<std::shared_ptr<const Product>(const GeometryParams&)>;

  /// For messages: field, the GeometryParams field naming the tag ("angular_binning"); kind, what the
  /// products are ("angular binning").
  TagRegistry(std::string field, std::string kind, std::map<std::string, Factory> built_ins)
      : field_(std::move(field)), kind_(std::move(kind)), factories_(std::move(built_ins)) {}

  void add(const std::string& tag, Factory factory) {
    require_parameter(!tag.empty() && tag.size() <= kMaxTagLength, (kind_ + " tag length").c_str(), tag.size(),
                      "in [1, 64]");
    std::lock_guard<std::mutex> lock(mutex_);
    factories_[tag] = std::move(factory);
  }

  std::vector<std::string> tags() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> tags;
    for (const auto& entry : factories_) tags.push_back(entry.first);
    return tags;
  }

  bool has(const std::string& tag) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return factories_.count(tag) != 0;
  }

  /// The product registered under `tag`; InvalidParameter naming the field and the registered tags when none is.
  std::shared_ptr<const Product> make(const std::string& tag, const GeometryParams& params) const {
    Factory factory;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto found = factories_.find(tag);
      if (found != factories_.end()) factory = found->second;
    }
    if (!factory) {
      std::string known;
      for (const std::string& t : tags()) known += (known.empty() ? "" : ", ") + t;
      throw InvalidParameter(field_ + " = '" + tag + "' is not a registered binning (registered: " + known + ")");
    }
    return factory(params);
  }

private:
  std::string field_, kind_;
  mutable std::mutex mutex_;
  std::map<std::string, Factory> factories_;
};

}  // namespace detail
}  // namespace occ_improve
