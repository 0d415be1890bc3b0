#include "report.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace pdfem
{
  void write_atomically(const std::filesystem::path &           path,
                        const std::function<void(std::ostream &)> &writer)
  {
    if (path.has_parent_path())
      std::filesystem::create_directories(path.parent_path());
    std::filesystem::path tmp = path;
    tmp += ".tmp";
    {
      std::ofstream out(tmp, std::ios::out | std::ios::trunc);
      if (!out)
        throw std::runtime_error("cannot open '" + tmp.string() +
                                 "' for writing");
      writer(out);
      out.flush();
      if (!out)
        throw std::runtime_error("error while writing '" + tmp.string() + "'");
    }
    std::filesystem::rename(tmp, path);
  }

  JsonWriter::JsonWriter(std::ostream &o)
    : out(o)
  {}

  std::string JsonWriter::escape(const std::string &s)
  {
    std::string r;
    r.reserve(s.size() + 2);
    for (const char c : s)
      switch (c)
        {
          case '"':
            r += "\\\"";
            break;
          case '\\':
            r += "\\\\";
            break;
          case '\n':
            r += "\\n";
            break;
          case '\t':
            r += "\\t";
            break;
          case '\r':
            r += "\\r";
            break;
          default:
            if (static_cast<unsigned char>(c) < 0x20)
              {
                char buf[8];
                std::snprintf(buf, sizeof buf, "\\u%04x",
                              static_cast<unsigned int>(c));
                r += buf;
              }
            else
              r += c;
        }
    return r;
  }

  std::string JsonWriter::number(double v)
  {
    if (!std::isfinite(v))
      return "null";
    std::ostringstream s;
    s << std::setprecision(std::numeric_limits<double>::max_digits10) << v;
    return s.str();
  }

  void JsonWriter::prefix(const std::string &key)
  {
    if (!first_in_scope.empty())
      {
        if (!first_in_scope.back())
          out << ',';
        first_in_scope.back() = false;
        out << '\n' << std::string(2 * first_in_scope.size(), ' ');
        if (!scope_is_array.back())
          out << '"' << escape(key) << "\": ";
      }
  }

  JsonWriter &JsonWriter::begin_object(const std::string &key)
  {
    prefix(key);
    out << '{';
    first_in_scope.push_back(true);
    scope_is_array.push_back(false);
    return *this;
  }

  JsonWriter &JsonWriter::end_object()
  {
    const bool empty = first_in_scope.back();
    first_in_scope.pop_back();
    scope_is_array.pop_back();
    if (!empty)
      out << '\n' << std::string(2 * first_in_scope.size(), ' ');
    out << '}';
    if (first_in_scope.empty())
      out << '\n';
    return *this;
  }

  JsonWriter &JsonWriter::begin_array(const std::string &key)
  {
    prefix(key);
    out << '[';
    first_in_scope.push_back(true);
    scope_is_array.push_back(true);
    return *this;
  }

  JsonWriter &JsonWriter::end_array()
  {
    const bool empty = first_in_scope.back();
    first_in_scope.pop_back();
    scope_is_array.pop_back();
    if (!empty)
      out << '\n' << std::string(2 * first_in_scope.size(), ' ');
    out << ']';
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, double v)
  {
    prefix(key);
    out << number(v);
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, int v)
  {
    prefix(key);
    out << v;
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, unsigned int v)
  {
    prefix(key);
    out << v;
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, unsigned long v)
  {
    prefix(key);
    out << v;
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, bool v)
  {
    prefix(key);
    out << (v ? "true" : "false");
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, const std::string &v)
  {
    prefix(key);
    out << '"' << escape(v) << '"';
    return *this;
  }

  JsonWriter &JsonWriter::value(const std::string &key, const char *v)
  {
    return value(key, std::string(v));
  }

  JsonWriter &JsonWriter::value(const std::string &          key,
                                const std::optional<double> &v)
  {
    if (v)
      return value(key, *v);
    return null(key);
  }

  JsonWriter &JsonWriter::null(const std::string &key)
  {
    prefix(key);
    out << "null";
    return *this;
  }

  JsonWriter &JsonWriter::raw(const std::string &key,
                              const std::string &json_text)
  {
    prefix(key);
    // Re-indent the foreign text so that it nests properly.
    const std::string indent(2 * first_in_scope.size(), ' ');
    std::string       text = json_text;
    while (!text.empty() && (text.back() == '\n' || text.back() == ' '))
      text.pop_back();
    for (const char c : text)
      {
        out << c;
        if (c == '\n')
          out << indent;
      }
    return *this;
  }

  Richardson richardson(const std::vector<double> &q, const double ratio)
  {
    Richardson r;
    if (q.empty())
      return r;
    r.extrapolated = q.back();
    if (q.size() < 2)
      {
        r.error_estimate = std::numeric_limits<double>::quiet_NaN();
        r.relative_error = std::numeric_limits<double>::quiet_NaN();
        return r;
      }
    const double q2 = q[q.size() - 1], q1 = q[q.size() - 2];
    r.error_estimate = std::abs(q2 - q1); // fallback: last difference
    if (q.size() >= 3)
      {
        const double q0 = q[q.size() - 3];
        const double d1 = q1 - q0, d2 = q2 - q1;
        if (d1 != 0. && d2 != 0. && (d1 > 0.) == (d2 > 0.) &&
            std::abs(d2) < std::abs(d1))
          {
            const double p = std::log(std::abs(d1) / std::abs(d2)) /
                             std::log(ratio);
            r.order          = p;
            r.extrapolated   = q2 + d2 / (std::pow(ratio, p) - 1.);
            r.error_estimate = std::abs(r.extrapolated - q2);
            r.valid          = true;
          }
        else if (d2 == 0.)
          {
            r.error_estimate = 0.;
            r.valid          = true;
          }
      }
    r.relative_error = (r.extrapolated != 0.) ?
                         r.error_estimate / std::abs(r.extrapolated) :
                         r.error_estimate;
    return r;
  }

  Richardson richardson(const std::vector<double> &q,
                        const std::vector<double> &h)
  {
    if (q.size() != h.size())
      throw std::invalid_argument("richardson: one mesh size per value");
    if (q.size() < 3)
      return richardson(q, 2.);
    const std::size_t n  = q.size();
    const double      r1 = h[n - 3] / h[n - 2], r2 = h[n - 2] / h[n - 1];
    if (std::abs(r1 - r2) <= 1e-12 * r2)
      return richardson(q, r2);

    Richardson   r;
    const double q0 = q[n - 3], q1 = q[n - 2], q2 = q[n - 1];
    const double d1 = q1 - q0, d2 = q2 - q1;
    r.extrapolated   = q2;
    r.error_estimate = std::abs(d2);
    // g(p) = (h0^p - h1^p) / (h1^p - h2^p) rises from ln(r1)/ln(r2) at
    // p -> 0; a solution p > 0 exists iff d1/d2 exceeds that limit.
    const auto g = [&](const double p) {
      return (std::pow(h[n - 3], p) - std::pow(h[n - 2], p)) /
             (std::pow(h[n - 2], p) - std::pow(h[n - 1], p));
    };
    const double target = (d2 != 0.) ? d1 / d2 : 0.;
    if (d2 == 0.)
      {
        r.error_estimate = 0.;
        r.valid          = true;
      }
    else if (target > std::log(r1) / std::log(r2) && target < g(20.))
      {
        double lo = 1e-9, hi = 20.;
        for (int it = 0; it < 200 && hi - lo > 1e-13; ++it)
          {
            const double mid = 0.5 * (lo + hi);
            (g(mid) < target ? lo : hi) = mid;
          }
        const double p = 0.5 * (lo + hi);
        r.order        = p;
        r.extrapolated = q2 - (q1 - q2) * std::pow(h[n - 1], p) /
                                (std::pow(h[n - 2], p) - std::pow(h[n - 1], p));
        r.error_estimate = std::abs(r.extrapolated - q2);
        r.valid          = true;
      }
    r.relative_error = (r.extrapolated != 0.) ?
                         r.error_estimate / std::abs(r.extrapolated) :
                         r.error_estimate;
    return r;
  }

  std::vector<Richardson>
  richardson_per_triple(const std::vector<double> &q,
                        const std::vector<double> &h)
  {
    std::vector<Richardson> triples;
    for (std::size_t k = 3; k <= q.size(); ++k)
      triples.push_back(
        richardson(std::vector<double>(q.begin(), q.begin() + k),
                   std::vector<double>(h.begin(), h.begin() + k)));
    return triples;
  }

  bool richardson_selftest()
  {
    bool       ok    = true;
    const auto check = [&](const char *what, const double value,
                           const double expected, const double tolerance) {
      const bool pass = std::abs(value - expected) <= tolerance;
      ok              = ok && pass;
      std::printf("%s %-58s %.12g (expected %.12g, tolerance %.1e)\n",
                  pass ? "PASS" : "FAIL", what, value, expected, tolerance);
    };
    const auto sequence = [](const std::vector<double> &h) {
      std::vector<double> q;
      for (const double hk : h)
        q.push_back(2.5e-4 - 3e-5 * std::pow(hk, 2.7)); // q_inf = 2.5e-4, p = 2.7
      return q;
    };
    // Unequal ratios 4/3 and 5/4: the order and the limit come back exactly.
    const std::vector<double> h{1. / 3., 1. / 4., 1. / 5.};
    const Richardson          r = richardson(sequence(h), h);
    check("unequal ratios: observed order", r.order.value_or(0.), 2.7, 1e-9);
    check("unequal ratios: extrapolated value", r.extrapolated, 2.5e-4, 1e-16);
    check("unequal ratios: error estimate = |q_inf - q2|", r.error_estimate,
          3e-5 * std::pow(0.2, 2.7), 1e-16);
    // Equal ratios: the same as the closed form of ratio 2.
    const std::vector<double> h2{1., 0.5, 0.25};
    const Richardson          a = richardson(sequence(h2), h2);
    const Richardson          b = richardson(sequence(h2), 2.);
    check("ratio 2 given as sizes: order as richardson(q, 2)",
          a.order.value_or(0.), b.order.value_or(-1.), 1e-12);
    check("ratio 2 given as sizes: extrapolated", a.extrapolated, 2.5e-4,
          1e-16);
    // Differences of opposite sign: no order, the last difference as estimate.
    const Richardson n = richardson({1.0, 1.2, 1.1}, h);
    check("sign change: valid (0 = no)", n.valid ? 1. : 0., 0., 0.);
    check("sign change: estimate = |q2 - q1|", n.error_estimate, 0.1, 1e-15);
    // Every triple of q_inf + C h^p has order p.
    const std::vector<double> h4{1. / 2., 1. / 3., 1. / 4., 1. / 5.};
    const auto triples = richardson_per_triple(sequence(h4), h4);
    check("richardson_per_triple: one per triple",
          static_cast<double>(triples.size()), 2., 0.);
    check("richardson_per_triple: first triple's order",
          triples.front().order.value_or(0.), 2.7, 1e-9);
    check("richardson_per_triple: second triple's limit",
          triples.back().extrapolated, 2.5e-4, 1e-16);
    return ok;
  }

  std::string iso_date_time()
  {
    const std::time_t t = std::time(nullptr);
    std::tm           tm{};
    localtime_r(&t, &tm);
    char buf[64];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S%z", &tm);
    return buf;
  }
} // namespace pdfem
