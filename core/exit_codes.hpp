// The one exit-status convention of every sweepmap command and process (docs/reference/
// exit-codes.md). A script can tell from the status alone whose problem it is: the input's,
// the caller's, or the device's.
#pragma once

namespace sweepmap {

enum ExitCode : int {
  kExitOk = 0,              // success
  kExitBadInput = 1,        // the input held a problem: corrupt data, a log of another rig kind,
                            // an empty log, no usable sweep (what was produced is kept)
  kExitUsage = 2,           // usage or config error: bad option, bad rig file, bad --out
  kExitDeviceIdentity = 3,  // the device answered but is not the model the rig file names
  kExitDeviceIo = 4,        // device or I/O failure: cannot open, read or write
};

}  // namespace sweepmap
