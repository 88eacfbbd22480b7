#pragma once
// A call that must throw E with a message naming `name` (the value, field or input refused).
#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace occ_improve::test {

template <class E>
void expect_throw_naming(const std::function<void()>& f, const std::string& name) {
  try {
    f();
    ADD_FAILURE() << "no exception, expected one naming " << name;
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
  }
}

}  // namespace occ_improve::test
