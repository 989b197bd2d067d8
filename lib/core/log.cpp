#include "core/log.h"

namespace rs {

Reporter& silentReporter() {
    static Reporter silent;  // stateless
    return silent;
}

}  // namespace rs
