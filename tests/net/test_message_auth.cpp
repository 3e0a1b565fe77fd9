// Signed messages: what a key signs verifies, and nothing else does; key files as the docs
// describe them, and nothing looser.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "net/message_auth.hpp"

namespace sweepmap::net {
namespace {

namespace fs = std::filesystem;

std::array<uint8_t, kAuthKeyBytes> keyOf(uint8_t seed) {
  std::array<uint8_t, kAuthKeyBytes> k{};
  for (size_t i = 0; i < k.size(); ++i) k[i] = static_cast<uint8_t>(seed + 7 * i);
  return k;
}

TEST(MessageAuth, WhatTheKeySignsVerifiesAndLeavesThePayloadFirst) {
  const MessageAuth auth(keyOf(1));
  const std::vector<uint8_t> payload = {1, 2, 3, 4, 5};
  const std::vector<uint8_t> s = auth.sign("IMU", payload.data(), payload.size());
  ASSERT_EQ(s.size(), payload.size() + kAuthTrailerBytes);
  EXPECT_TRUE(std::equal(payload.begin(), payload.end(), s.begin()));  // decoders read this
  EXPECT_EQ(auth.verify("IMU", s.data(), s.size()), std::optional<size_t>(payload.size()));
  const std::vector<uint8_t> empty_signed = auth.sign("E", nullptr, 0);
  EXPECT_EQ(auth.verify("E", empty_signed.data(), empty_signed.size()), std::optional<size_t>(0));
}

TEST(MessageAuth, AnyChangeOrAnotherKeyFailsVerification) {
  const MessageAuth auth(keyOf(1));
  const std::vector<uint8_t> payload(100, 9);
  const std::vector<uint8_t> s = auth.sign("IMU", payload.data(), payload.size());
  EXPECT_FALSE(auth.verify("IMU2", s.data(), s.size()));  // replayed on another channel
  for (size_t i = 0; i < s.size(); i += 7) {
    std::vector<uint8_t> t = s;
    t[i] ^= 0x01;
    EXPECT_FALSE(auth.verify("IMU", t.data(), t.size())) << "byte " << i;
  }
  EXPECT_FALSE(auth.verify("IMU", s.data(), s.size() - 1));
  EXPECT_FALSE(auth.verify("IMU", payload.data(), payload.size()));  // unsigned
  EXPECT_FALSE(auth.verify("IMU", s.data(), 3));
  const MessageAuth other(keyOf(2));
  EXPECT_FALSE(other.verify("IMU", s.data(), s.size()));
}

class KeyFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sweepmap_key_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& bytes, mode_t mode) {
    const std::string p = (dir_ / "key").string();
    std::ofstream(p, std::ios::binary) << bytes;
    ::chmod(p.c_str(), mode);
    return p;
  }
  fs::path dir_;
};

TEST_F(KeyFile, RawAndHexKeysAreTheSameKey) {
  const std::array<uint8_t, kAuthKeyBytes> k = keyOf(3);
  const std::string raw(k.begin(), k.end());
  const std::vector<uint8_t> payload = {4, 2};
  const auto s = MessageAuth::fromKeyFile(write(raw, 0600)).sign("C", payload.data(), 2);
  std::string hex;
  for (uint8_t b : k) {
    char two[3];
    std::snprintf(two, sizeof two, "%02x", b);
    hex += two;
  }
  EXPECT_TRUE(MessageAuth::fromKeyFile(write(hex + "\n", 0400)).verify("C", s.data(), s.size()));
}

TEST_F(KeyFile, LooseModesWrongSizesAndMissingFilesAreRefusedWithTheFix) {
  const std::string raw(32, 'k');
  try {
    MessageAuth::fromKeyFile(write(raw, 0644));
    FAIL() << "a world-readable key was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chmod 600"), std::string::npos) << e.what();
  }
  EXPECT_THROW(MessageAuth::fromKeyFile(write(std::string(31, 'k'), 0600)), std::invalid_argument);
  EXPECT_THROW(MessageAuth::fromKeyFile(write(std::string(64, 'z'), 0600)), std::invalid_argument);
  EXPECT_THROW(MessageAuth::fromKeyFile((dir_ / "none").string()), std::invalid_argument);
  EXPECT_THROW(MessageAuth::fromKeyFile(dir_.string()), std::invalid_argument);
}

}  // namespace
}  // namespace sweepmap::net
