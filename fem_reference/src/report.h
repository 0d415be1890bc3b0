// Small helpers for pd-fem output: atomic file writes, a minimal JSON writer
// and Richardson extrapolation of a sequence of refinement levels.
#pragma once

#include <functional>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace pdfem
{
  // Write a file "atomically": the content goes to PATH.tmp, which is then
  // renamed to PATH.  A run that is interrupted never leaves a truncated PATH.
  void write_atomically(const std::filesystem::path &           path,
                        const std::function<void(std::ostream &)> &writer);

  // A tiny streaming JSON writer (objects, arrays, numbers, strings, bools,
  // null), enough for summary.json.  It keeps track of commas and indentation.
  class JsonWriter
  {
  public:
    explicit JsonWriter(std::ostream &out);

    JsonWriter &begin_object(const std::string &key = "");
    JsonWriter &end_object();
    JsonWriter &begin_array(const std::string &key = "");
    JsonWriter &end_array();

    JsonWriter &value(const std::string &key, double v);
    JsonWriter &value(const std::string &key, int v);
    JsonWriter &value(const std::string &key, unsigned int v);
    JsonWriter &value(const std::string &key, unsigned long v);
    JsonWriter &value(const std::string &key, bool v);
    JsonWriter &value(const std::string &key, const std::string &v);
    JsonWriter &value(const std::string &key, const char *v);
    JsonWriter &value(const std::string &key, const std::optional<double> &v);
    JsonWriter &null(const std::string &key);
    // Insert already formatted JSON text (e.g. deal.II's parameter dump).
    JsonWriter &raw(const std::string &key, const std::string &json_text);

    static std::string escape(const std::string &s);
    static std::string number(double v);

  private:
    void prefix(const std::string &key);

    std::ostream &    out;
    std::vector<bool> first_in_scope;
    std::vector<bool> scope_is_array;
  };

  // Richardson extrapolation from the last three values q0, q1, q2 of a
  // sequence of uniformly refined meshes (ratio r between mesh sizes).
  //   observed order   p     = log(|q1 - q0| / |q2 - q1|) / log(r)
  //   extrapolated     q_ext = q2 + (q2 - q1) / (r^p - 1)
  //   error estimate   e     = |q_ext - q2|  (of the finest value q2)
  // If the differences change sign or vanish, the sequence is not in the
  // asymptotic range: no order is reported and the error estimate falls back
  // to the (pessimistic) last difference |q2 - q1|.
  struct Richardson
  {
    bool                  valid = false; // three values in asymptotic range?
    std::optional<double> order;
    double                extrapolated    = 0.;
    double                error_estimate  = 0.; // absolute, of the finest value
    double                relative_error  = 0.; // error_estimate / |q_ext|
  };

  Richardson richardson(const std::vector<double> &values, double ratio = 2.0);

  // The same from the last three values of a sequence whose mesh sizes h
  // (any unit, decreasing) need not shrink by one constant ratio: the
  // order p solves (q1 - q0) / (q2 - q1) = (h0^p - h1^p) / (h1^p - h2^p),
  // whose right side grows monotonically with p (bisection), and
  //   q_ext = q2 - (q1 - q2) h2^p / (h1^p - h2^p).
  // With a constant ratio this is richardson(values, ratio) above.  If the
  // differences change sign, or shrink too slowly for any p > 0, the
  // estimate falls back to |q2 - q1| as there.
  Richardson richardson(const std::vector<double> &values,
                        const std::vector<double> &mesh_sizes);

  // The extrapolation of every three consecutive levels: a reference is
  // demonstrated converged where their orders settle and their extrapolated
  // values agree, not by the last triple alone.
  std::vector<Richardson>
  richardson_per_triple(const std::vector<double> &values,
                        const std::vector<double> &mesh_sizes);

  // pd-fem --richardson-selftest: both forms above on sequences
  // q = q_inf + C h^p with known q_inf and p (equal and unequal ratios) and
  // on one whose differences change sign; prints a line per check and
  // returns whether all pass.
  bool richardson_selftest();

  // Current date/time as ISO 8601 (local time with offset).
  std::string iso_date_time();
} // namespace pdfem
