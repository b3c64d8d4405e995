// The Weber-law elbow of thesis Fig. 4.5, without its out-of-bounds read (k = len), its read of an empty list,
// and with the comparison its code makes (the current candidate against the running total).
#include "envlight.h"

namespace prt::envlight {

size_t elbowCount(const double* values, size_t count, double threshold) {
    if (count == 0) return 0;
    double total = values[0];
    size_t k = 1; // the first candidate's share is 1
    while (k < count) {
        total += values[k];
        if (!(total > 0.0) || values[k] / total <= threshold) break;
        ++k;
    }
    return k;
}

} // namespace prt::envlight
