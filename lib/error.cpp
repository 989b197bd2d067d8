#include "error.h"

namespace rs {

const char* errorKindName(ErrorKind kind) {
    switch (kind) {
        case ErrorKind::Io: return "io";
        case ErrorKind::Scene: return "scene";
        case ErrorKind::Config: return "config";
        case ErrorKind::Gpu: return "gpu";
        case ErrorKind::Embree: return "embree";
        case ErrorKind::Internal: return "internal";
    }
    return "?";
}

}  // namespace rs
