#pragma once

// The eDVS4337 serial protocol as a whole, for code that speaks all of it (the device class, the
// emulator): event formats, command lines, bias registers, the timestamp unwrapper, the parser,
// format detection and the encoder. Each part has its own header; include only the one you use.

#include "edvs/biases.h"
#include "edvs/commands.h"
#include "edvs/event_encoder.h"
#include "edvs/event_format.h"
#include "edvs/event_parser.h"
#include "edvs/format_detection.h"
#include "edvs/timestamp_unwrapper.h"
