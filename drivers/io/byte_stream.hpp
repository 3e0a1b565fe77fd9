// Byte transports to a device: a TCP socket or a termios serial port. Blocking calls with
// timeouts (poll(2)), no threads of their own; a hang-up or an I/O error is a StreamError
// whose message names the device.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

namespace sweepmap {

class StreamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  // Waits up to timeout_ms for input, then reads what is there (at most `capacity` bytes).
  // Returns 0 on timeout. Throws StreamError on hang-up or error.
  virtual size_t read(uint8_t* buffer, size_t capacity, int timeout_ms) = 0;
  // Writes all of `data` within timeout_ms, or throws StreamError.
  virtual void write(const void* data, size_t size, int timeout_ms = 1000) = 0;
  void write(const std::string& s, int timeout_ms = 1000) { write(s.data(), s.size(), timeout_ms); }
  // Discards input already received (the kernel's buffer and what arrives within quiet_ms).
  void drain(int quiet_ms);
  // Serial ports: the DTR line (YDLIDAR X4 motor enable, RPLIDAR A1 motor on USB adapters).
  virtual void setDtr(bool on) {}
  virtual int fd() const = 0;
  // "tcp 127.0.0.1:10940", "serial /dev/ttyUSB0 @128000": for messages.
  virtual std::string describe() const = 0;
};

// Connects within timeout_ms. Throws StreamError: "tcp HOST:PORT: connection refused".
std::unique_ptr<ByteStream> openTcp(const std::string& host, int port, int timeout_ms);
// Opens a serial port raw (8N1, no flow control) at `baud` (any rate the driver accepts,
// e.g. 128000 for the X4 via termios2). Throws StreamError: "serial /dev/ttyUSB0: no such
// file or directory".
std::unique_ptr<ByteStream> openSerial(const std::string& path, int baud);

}  // namespace sweepmap
