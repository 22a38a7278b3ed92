// Doubles rounded to float and kept as float: vectorized, never widened back; the script
// must not list it.
struct Pair {
  float x, y;
};

void keptSingle(Pair* out, const double* a) {
  out->x = static_cast<float>(a[0]);
  out->y = static_cast<float>(a[1]);
}
