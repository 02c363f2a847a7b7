/* dump_oiio.cpp - wall/dump.h's image files on top of OpenImageIO (the project's one C++
 * file), built as the image module that wall/dump.c loads on first use (why a module:
 * wall/dump_module.h). Its one export, tessera_dump_module, hands out the table of the
 * functions below; it is linked with its own copies of engine/base/err.c and engine/base/srgb8.c.
 *
 * Boundary rule: every function of the table runs its body inside guarded(), so
 * no C++ exception ever unwinds into C; exceptions and OIIO failures become a
 * tess_error "PATH: what failed: OIIO's message". Every OIIO call that can
 * fail is checked, including close(), and a file left behind by a failed
 * write is removed so a partial frame is never mistaken for a good one. */

#include "engine/base/err.h"
#include "engine/base/srgb.h"
#include "dump.h"
#include "dump_module.h"
#include "engine/base/srgb8.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace {

/* the host's I/O calls (dump_module.h), set by tessera_dump_module before any other call */
const dump_module_io *host_io;

const char *shown(const char *s) { return s ? s : "(null)"; }

/* OIIO's message on one line ("; " between its lines), never empty. */
std::string one_line(std::string msg)
{
    while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' '))
        msg.pop_back();
    for (size_t at = msg.find('\n'); at != std::string::npos; at = msg.find('\n', at))
        msg.replace(at, 1, "; ");
    return msg.empty() ? std::string("unknown OpenImageIO error") : msg;
}

/* The error of a failed call on `obj`, or the global one if it left none;
 * both are consumed so a stale message never leaks into a later report. */
template <class T> std::string oiio_error(const T &obj)
{
    std::string own = obj.geterror();
    std::string global = OIIO::geterror();
    return one_line(own.empty() ? global : own);
}

std::string oiio_global_error() { return one_line(OIIO::geterror()); }

/* Run `body` with every C++ exception turned into an error naming `path`. */
template <class F> bool guarded(const char *path, tess_error *err, F &&body)
{
    try {
        return body();
    } catch (const std::exception &e) {
        return tess_error_set(err, "%s: %s", shown(path), e.what());
    } catch (...) {
        return tess_error_set(err, "%s: unknown C++ exception", shown(path));
    }
}

/* The file name extension after the last '.' of the last path component,
 * lower-cased; "" when there is none. */
std::string extension_of(const char *path)
{
    const char *base = std::strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = std::strrchr(base, '.');
    std::string ext = (dot && dot != base) ? dot + 1 : "";
    for (char &c : ext)
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
    return ext;
}

/* Formats that keep linear float values; everything else gets 8-bit sRGB. */
bool is_float_format(const std::string &ext)
{
    return ext == "exr" || ext == "sxr" || ext == "mxr" || ext == "hdr" || ext == "rgbe" || ext == "pfm";
}

/* Removes `path` on scope exit unless `keep` is set. */
struct remove_unless_kept {
    const char *path;
    bool keep;
    ~remove_unless_kept()
    {
        if (!keep)
            std::remove(path);
    }
};

/* The output file as an OIIO IOProxy that keeps the first I/O failure.
 * With OIIO 2.4 writing files itself, a PNG written to a full disk
 * (/dev/full) is reported as a success; through this proxy the failure is
 * read back after close(). Reads are served too, as a writer may read back
 * what it wrote. */
class checked_file final : public OIIO::Filesystem::IOProxy {
public:
    checked_file() = default;
    ~checked_file() override { close(); }
    checked_file(const checked_file &) = delete;
    checked_file &operator=(const checked_file &) = delete;

    /* Create or truncate `path`; false with errno set. */
    bool create(const char *path)
    {
        fd_ = ::open(path, O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
        if (fd_ < 0)
            return false;
        m_filename = path;
        m_mode = Write;
        m_pos = 0;
        return true;
    }
    /* errno of the first failed call, 0 when all succeeded. */
    int first_errno() const { return errno_.load(); }

    const char *proxytype() const override { return "tessera_checked_file"; }
    void close() override
    {
        if (fd_ >= 0 && host_io->close(fd_) != 0)
            fail(errno);
        fd_ = -1;
        m_mode = Closed;
    }
    bool seek(int64_t offset) override
    {
        if (offset < 0) {
            fail(EINVAL);
            return false;
        }
        m_pos = offset;
        return true;
    }
    size_t write(const void *buf, size_t size) override
    {
        size_t done = pwrite(buf, size, m_pos);
        m_pos += (int64_t)done;
        return done;
    }
    size_t read(void *buf, size_t size) override
    {
        size_t done = pread(buf, size, m_pos);
        m_pos += (int64_t)done;
        return done;
    }
    /* pwrite/pread may run on several threads at once (OIIO's contract). */
    size_t pwrite(const void *buf, size_t size, int64_t offset) override
    {
        size_t done = 0;
        while (done < size) {
            ssize_t n = host_io->pwrite(fd_, (const char *)buf + done, size - done, (off_t)offset + (off_t)done);
            if (n < 0 && errno == EINTR)
                continue;
            if (n <= 0) {
                fail(n < 0 ? errno : EIO);
                break;
            }
            done += (size_t)n;
        }
        return done;
    }
    size_t pread(void *buf, size_t size, int64_t offset) override
    {
        size_t done = 0;
        while (done < size) {
            ssize_t n = ::pread(fd_, (char *)buf + done, size - done, (off_t)offset + (off_t)done);
            if (n < 0 && errno == EINTR)
                continue;
            if (n < 0)
                fail(errno);
            if (n <= 0) /* end of file is no failure: a short read reports it */
                break;
            done += (size_t)n;
        }
        return done;
    }
    size_t size() const override
    {
        struct stat st;
        return fd_ >= 0 && fstat(fd_, &st) == 0 ? (size_t)st.st_size : 0;
    }

private:
    void fail(int e)
    {
        int none = 0;
        errno_.compare_exchange_strong(none, e ? e : EIO);
    }

    int fd_ = -1;                 /* open from create() to close() */
    std::atomic<int> errno_ {0}; /* first failure; written by any thread in pwrite */
};

bool write_rgb(const char *path, int width_px, int height_px, const float *rgb_linear, tess_error *err)
{
    if (!path || !*path)
        return tess_error_set(err, "dump: no output path");
    if (width_px <= 0 || height_px <= 0)
        return tess_error_set(err, "%s: image size %dx%d: width and height must be positive", path, width_px,
                              height_px);
    if (!rgb_linear)
        return tess_error_set(err, "%s: no pixel data", path);

    /* Declared before `out`, whose destructor may still write to it. */
    checked_file file;

    auto out = OIIO::ImageOutput::create(path);
    if (!out)
        return tess_error_set(err, "%s: cannot write this format: %s", path, oiio_global_error().c_str());

    const size_t values = (size_t)width_px * (size_t)height_px * 3;
    const bool as_float = is_float_format(extension_of(path));
    /* Float formats get the caller's buffer as is (FLOAT, not HALF: frames
     * are references and must round-trip bit exact); 8-bit ones get a
     * converted copy. */
    std::vector<uint8_t> encoded;
    OIIO::ImageSpec spec(width_px, height_px, 3, as_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
    const void *pixels = rgb_linear;
    if (as_float) {
        spec.attribute("oiio:ColorSpace", "Linear");
    } else {
        spec.attribute("oiio:ColorSpace", "sRGB");
        encoded.resize(values);
        srgb8_encode_values(rgb_linear, values, encoded.data());
        pixels = encoded.data();
    }

    /* Formats that take an IOProxy write through `file`, created first so
     * an unwritable path fails before any encoding. The others are written
     * by OIIO itself, whose write failures may pass unnoticed: SGI, HEIF,
     * FITS, ... (no proxy support) and TIFF, whose 2.4 writer makes
     * unreadable files through any proxy once metadata such as
     * oiio:ColorSpace is set (fixed upstream by OIIO pull request 4300). */
    const bool checked = out->supports("ioproxy") != 0 && std::strcmp(out->format_name(), "tiff") != 0;
    remove_unless_kept partial{path, true}; /* armed once the file exists */
    if (checked) {
        if (!file.create(path))
            return tess_error_set(err, "%s: cannot open for writing: %s", path, std::strerror(errno));
        partial.keep = false;
        if (!out->set_ioproxy(&file))
            return tess_error_set(err, "%s: cannot write through a checked file: %s", path, oiio_error(*out).c_str());
    }
    /* A write through `file` that failed is the cause of whatever OIIO then
     * says (OpenEXR writes its header in open() and says only "File output
     * failed"): name the system's error first. */
    auto failed = [&](const char *what) {
        if (checked && file.first_errno() != 0)
            return tess_error_set(err, "%s: write failed (file incomplete): %s (%s: %s)", path,
                                  std::strerror(file.first_errno()), what, oiio_error(*out).c_str());
        return tess_error_set(err, "%s: %s: %s", path, what, oiio_error(*out).c_str());
    };
    if (!out->open(path, spec))
        return failed("cannot open for writing");
    partial.keep = false;
    if (!out->write_image(spec.format, pixels))
        return failed("write failed");
    if (!out->close())
        return failed("close failed (file incomplete)");
    if (checked) {
        file.close();
        if (file.first_errno() != 0)
            return tess_error_set(err, "%s: write failed (file incomplete): %s", path,
                                  std::strerror(file.first_errno()));
    }
    partial.keep = true;
    return true;
}

/* free() for unique_ptr, so a throw between malloc and the hand-over frees. */
struct free_deleter {
    void operator()(void *p) const { std::free(p); }
};

/* Read the first subimage of `path` as 3 channels of T: grey (1 or 2
 * channels) is replicated, channels past the third (alpha) are dropped. */
/* A directory or a device is no image: said before OpenImageIO tries every
 * reader on it (libheif's, given a directory, allocates for minutes under
 * ASan's slow unwinding). A path that does not exist is left to OIIO's message. */
bool not_a_file(const char *path, tess_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0 || S_ISREG(st.st_mode))
        return false;
    tess_error_set(err, "%s: cannot read: %s, not an image file", path,
                   S_ISDIR(st.st_mode) ? "it is a directory" : "it is not a regular file");
    return true;
}

template <class T>
bool read_rgb(const char *path, OIIO::TypeDesc type, int *width_px, int *height_px, T **rgb_out,
              tess_error *err)
{
    if (!path || !width_px || !height_px || !rgb_out)
        return tess_error_set(err, "%s: dump_read: NULL argument", shown(path));
    *width_px = *height_px = 0;
    *rgb_out = nullptr;

    /* Keep colour values as stored: without this hint OIIO premultiplies
     * them by alpha on read (PNG, TGA...), which dropping alpha would bake in. */
    if (not_a_file(path, err))
        return false;
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in)
        return tess_error_set(err, "%s: cannot read: %s", path, oiio_global_error().c_str());

    const OIIO::ImageSpec &spec = in->spec();
    if (spec.width <= 0 || spec.height <= 0 || spec.depth != 1 || spec.nchannels <= 0)
        return tess_error_set(err, "%s: unsupported image shape %dx%dx%d with %d channels", path, spec.width,
                              spec.height, spec.depth, spec.nchannels);
    const int w = spec.width, h = spec.height;
    const size_t values = (size_t)w * (size_t)h * 3;
    std::unique_ptr<T, free_deleter> rgb((T *)std::malloc(values * sizeof(T)));
    if (!rgb)
        return tess_error_set(err, "%s: out of memory for %dx%d pixels", path, w, h);

    const bool grey = spec.nchannels < 3;
    const OIIO::stride_t pixel_bytes = 3 * (OIIO::stride_t)sizeof(T);
    if (!in->read_image(0, 0, 0, grey ? 1 : 3, type, rgb.get(), pixel_bytes, pixel_bytes * w))
        return tess_error_set(err, "%s: read failed: %s", path, oiio_error(*in).c_str());
    if (!in->close())
        return tess_error_set(err, "%s: close failed: %s", path, oiio_error(*in).c_str());
    if (grey) {
        T *p = rgb.get();
        for (size_t i = 0; i < values; i += 3)
            p[i + 1] = p[i + 2] = p[i];
    }
    *width_px = w;
    *height_px = h;
    *rgb_out = rgb.release();
    return true;
}

bool read_linear_rgb(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err)
{
    if (!path || !width_px || !height_px || !rgb_out)
        return tess_error_set(err, "%s: dump_read: NULL argument", shown(path));
    *width_px = *height_px = 0;
    *rgb_out = nullptr;
    /* What the file stores decides the encoding; a second open is cheap
     * next to decoding the pixels. */
    if (not_a_file(path, err))
        return false;
    bool stored_float;
    {
        auto in = OIIO::ImageInput::open(path);
        if (!in)
            return tess_error_set(err, "%s: cannot read: %s", path, oiio_global_error().c_str());
        stored_float = in->spec().format.is_floating_point();
        in->close();
    }
    if (stored_float)
        return read_rgb<float>(path, OIIO::TypeDesc::FLOAT, width_px, height_px, rgb_out, err);

    /* Integer formats through 16 bits (OIIO widens 8-bit values exactly,
     * v * 257) and a table of the 65536 decoded values. */
    uint16_t *codes = nullptr;
    if (!read_rgb<uint16_t>(path, OIIO::TypeDesc::UINT16, width_px, height_px, &codes, err))
        return false;
    std::unique_ptr<uint16_t, free_deleter> owned(codes);
    const size_t values = (size_t)*width_px * (size_t)*height_px * 3;
    std::unique_ptr<float, free_deleter> rgb((float *)std::malloc(values * sizeof(float)));
    if (!rgb) {
        tess_error_set(err, "%s: out of memory for %dx%d pixels", path, *width_px, *height_px);
        *width_px = *height_px = 0;
        return false;
    }
    std::vector<float> table(65536);
    for (size_t v = 0; v < table.size(); v++)
        table[v] = (float)srgb_curve_decode((double)v / 65535.0);
    for (size_t i = 0; i < values; i++)
        rgb.get()[i] = table[codes[i]];
    *rgb_out = rgb.release();
    return true;
}

} // namespace

extern "C" {

namespace {
bool module_write_rgb(const char *path, int width_px, int height_px, const float *rgb_linear, tess_error *err)
{
    return guarded(path, err, [&] { return write_rgb(path, width_px, height_px, rgb_linear, err); });
}

bool module_read_rgb8(const char *path, int *width_px, int *height_px, uint8_t **rgb_out, tess_error *err)
{
    return guarded(path, err,
                   [&] { return read_rgb<uint8_t>(path, OIIO::TypeDesc::UINT8, width_px, height_px, rgb_out, err); });
}

bool module_read_rgbf(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err)
{
    return guarded(path, err,
                   [&] { return read_rgb<float>(path, OIIO::TypeDesc::FLOAT, width_px, height_px, rgb_out, err); });
}

bool module_read_linear_rgb(const char *path, int *width_px, int *height_px, float **rgb_out, tess_error *err)
{
    return guarded(path, err, [&] { return read_linear_rgb(path, width_px, height_px, rgb_out, err); });
}

const dump_module_ops module_ops = {DUMP_MODULE_ABI, module_write_rgb, module_read_rgb8, module_read_rgbf,
                                    module_read_linear_rgb};
} // namespace

/* the module's one export (dump_module.h); the host calls it once, before any other call */
__attribute__((visibility("default"))) const dump_module_ops *tessera_dump_module(const dump_module_io *io);
const dump_module_ops *tessera_dump_module(const dump_module_io *io)
{
    if (!io || io->abi != DUMP_MODULE_ABI || !io->pwrite || !io->close)
        return nullptr;
    host_io = io;
    return &module_ops;
}

} // extern "C"
