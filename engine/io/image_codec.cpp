#include "engine/io/image_codec.h"

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <limits>
#include <png.h>
#include <jpeglib.h>
#include <jerror.h>

#include "engine/io/file_bytes.h"

// stb_image for BMP only; static so that a program embedding its own stb does not clash.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_BMP
#define STBI_NO_STDIO
#define STBI_NO_LINEAR
#define STBI_NO_HDR
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#endif
#include <stb/stb_image.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace vtloc::io {

namespace {

bool host_little_endian() {
    const uint16_t one = 1;
    uint8_t first = 0;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

// libpng and libjpeg report errors by longjmp; no C++ object is created between
// a setjmp and the library calls that may jump back to it, so none is skipped.
struct PngIo {
    const uint8_t* bytes = nullptr;
    size_t size = 0, pos = 0;
    std::vector<uint8_t>* out = nullptr;
    char message[256] = {};
};

void png_on_error(png_structp png, png_const_charp msg) {
    auto* io = static_cast<PngIo*>(png_get_error_ptr(png));
    std::snprintf(io->message, sizeof io->message, "%s", msg);
    png_longjmp(png, 1);
}
void png_on_warning(png_structp, png_const_charp) {}

void png_read_bytes(png_structp png, png_bytep dst, size_t n) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    if (n > io->size - io->pos) png_error(png, "the file ends inside the image");
    std::memcpy(dst, io->bytes + io->pos, n);
    io->pos += n;
}

void png_write_bytes(png_structp png, png_bytep src, size_t n) {
    auto* io = static_cast<PngIo*>(png_get_io_ptr(png));
    io->out->insert(io->out->end(), src, src + n);
}
void png_flush(png_structp) {}

// Returns false with io.message set when libpng refuses the data.
bool png_decode(PngIo& io, StoredImage& im, std::vector<png_bytep>& rows) {
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, png_on_error, png_on_warning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
        return false;
    }
    png_set_read_fn(png, &io, png_read_bytes);
    png_read_info(png, info);
    const int type = png_get_color_type(png, info), depth = png_get_bit_depth(png, info);
    if (type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
    if (depth == 16 && host_little_endian()) png_set_swap(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    im.width = int(png_get_image_width(png, info));
    im.height = int(png_get_image_height(png, info));
    im.channels = png_get_channels(png, info);
    im.bits = png_get_bit_depth(png, info);
    if (png_get_rowbytes(png, info) != im.row_bytes()) png_error(png, "unexpected row layout");
    im.data.resize(im.row_bytes() * size_t(im.height));
    rows.resize(size_t(im.height));
    for (int y = 0; y < im.height; ++y) rows[size_t(y)] = im.data.data() + size_t(y) * im.row_bytes();
    png_read_image(png, rows.data());
    png_read_end(png, nullptr);
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
}

struct JpegError {
    jpeg_error_mgr mgr;
    std::jmp_buf jump;
    char message[JMSG_LENGTH_MAX];
};

void jpeg_on_error(j_common_ptr c) {
    auto* e = reinterpret_cast<JpegError*>(c->err);
    c->err->format_message(c, e->message);
    std::longjmp(e->jump, 1);
}

// Warnings are ignored as OpenCV and PIL do, except data that ends early: that
// image would be finished in grey, which is garbage to a localiser.
void jpeg_on_message(j_common_ptr c, int level) {
    if (level < 0 && c->err->msg_code == JWRN_JPEG_EOF) c->err->error_exit(c);
}

// A crafted progressive JPEG can ask for thousands of scans, each a full pass.
void jpeg_on_progress(j_common_ptr c) {
    auto* d = reinterpret_cast<j_decompress_ptr>(c);
    if (d->input_scan_number > 1000) {
        auto* e = reinterpret_cast<JpegError*>(c->err);
        std::snprintf(e->message, sizeof e->message, "more than 1000 progressive scans");
        std::longjmp(e->jump, 1);
    }
}

bool jpeg_decode(const std::vector<uint8_t>& bytes, StoredImage& im, JpegError& err) {
    jpeg_decompress_struct d;
    jpeg_progress_mgr progress;
    d.err = jpeg_std_error(&err.mgr);
    err.mgr.error_exit = jpeg_on_error;
    err.mgr.emit_message = jpeg_on_message;
    err.message[0] = 0;
    if (setjmp(err.jump)) {
        jpeg_destroy_decompress(&d);
        return false;
    }
    jpeg_create_decompress(&d);
    progress.progress_monitor = jpeg_on_progress;
    d.progress = &progress;
    jpeg_mem_src(&d, bytes.data(), static_cast<unsigned long>(bytes.size()));
    jpeg_read_header(&d, TRUE);
    if (d.jpeg_color_space == JCS_CMYK || d.jpeg_color_space == JCS_YCCK) {
        std::snprintf(err.message, sizeof err.message, "a CMYK JPEG (only grey and colour JPEGs are read)");
        jpeg_destroy_decompress(&d);
        return false;
    }
    d.out_color_space = d.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
    jpeg_start_decompress(&d);
    im.width = int(d.output_width);
    im.height = int(d.output_height);
    im.channels = d.output_components;
    im.bits = 8;
    im.data.resize(im.row_bytes() * size_t(im.height));
    while (d.output_scanline < d.output_height) {
        JSAMPROW row = im.data.data() + size_t(d.output_scanline) * im.row_bytes();
        jpeg_read_scanlines(&d, &row, 1);
    }
    jpeg_finish_decompress(&d);
    jpeg_destroy_decompress(&d);
    return true;
}

bool is_png(const std::vector<uint8_t>& b) { return b.size() >= 8 && std::memcmp(b.data(), "\x89PNG\r\n\x1a\n", 8) == 0; }
bool is_jpeg(const std::vector<uint8_t>& b) { return b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF; }
bool is_bmp(const std::vector<uint8_t>& b) { return b.size() >= 2 && b[0] == 'B' && b[1] == 'M'; }

uint32_t be16(const uint8_t* p) { return uint32_t(p[0]) << 8 | p[1]; }
uint32_t be32(const uint8_t* p) { return be16(p) << 16 | be16(p + 2); }
uint32_t le32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

// The largest side accepted: far above any tactile frame or depth camera, far
// below what would let a forged header allocate gigabytes.
constexpr uint32_t kMaxImageSide = 8192;

// Only PNG, JPEG and BMP are decoded, and their size is read from the header
// before any decoder allocates for it (when OpenCV decoded, a fuzzer led a
// ".png" with a DICOM body into a 2.6 GB allocation).
void check_header(const std::vector<uint8_t>& b, const std::string& path) {
    const size_t n = b.size();
    uint32_t w = 0, h = 0;
    if (is_png(b) && n >= 24 && std::memcmp(&b[12], "IHDR", 4) == 0) {
        w = be32(&b[16]), h = be32(&b[20]);
    } else if (is_bmp(b) && n >= 26) {
        w = le32(&b[18]);
        const int32_t sh = int32_t(le32(&b[22]));  // negative: rows stored top-down
        h = sh < 0 ? uint32_t(-int64_t(sh)) : uint32_t(sh);
    } else if (is_jpeg(b)) {
        for (size_t i = 2; i + 9 < n && !w;) {  // segments until a start-of-frame marker
            if (b[i] != 0xFF) fail(path, "JPEG data is corrupt (no marker where one belongs)");
            const uint8_t m = b[i + 1];
            if (m == 0xFF) { ++i; continue; }
            if (m == 0xDA || m == 0xD9) break;  // scan data or end before any frame header
            if (m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC) h = be16(&b[i + 5]), w = be16(&b[i + 7]);
            i += 2 + be16(&b[i + 2]);
        }
        if (!w || !h) fail(path, "JPEG data is corrupt (no frame header with the image size)");
    } else {
        fail(path, "not an image this engine reads (PNG, JPEG or BMP; other formats are refused)");
    }
    if (w == 0 || h == 0 || w > kMaxImageSide || h > kMaxImageSide)
        fail(path, "the image header says " + std::to_string(w) + "x" + std::to_string(h) + " pixels; at most " +
                       std::to_string(kMaxImageSide) + " a side is read");
}

}  // namespace

StoredImage decode_image(const std::vector<uint8_t>& bytes, const std::string& path) {
    check_header(bytes, path);
    StoredImage im;
    if (is_png(bytes)) {
        PngIo io;
        io.bytes = bytes.data();
        io.size = bytes.size();
        std::vector<png_bytep> rows;
        if (!png_decode(io, im, rows)) fail(path, std::string("PNG data is corrupt or truncated (") + io.message + ")");
    } else if (is_jpeg(bytes)) {
        JpegError err;
        if (!jpeg_decode(bytes, im, err)) fail(path, std::string("JPEG data is corrupt or truncated (") + err.message + ")");
    } else {  // BMP: check_header admits nothing else
        if (bytes.size() > size_t(std::numeric_limits<int>::max())) fail(path, "the BMP file is too large");
        int w = 0, h = 0, c = 0;
        stbi_uc* p = stbi_load_from_memory(bytes.data(), int(bytes.size()), &w, &h, &c, 0);
        if (!p) fail(path, std::string("BMP data is corrupt or of a kind not read (") + stbi_failure_reason() + ")");
        im.width = w, im.height = h, im.channels = c, im.bits = 8;
        im.data.assign(p, p + im.row_bytes() * size_t(h));
        stbi_image_free(p);
    }
    if (im.width <= 0 || im.height <= 0) fail(path, "the image has no pixels");
    return im;
}

uint16_t StoredImage::sample16(size_t i) const {
    uint16_t v = 0;
    std::memcpy(&v, data.data() + 2 * i, 2);
    return v;
}

void StoredImage::swap_red_blue() {
    if (channels < 3) return;
    const size_t sample = size_t(bits / 8), pixel = sample * size_t(channels);
    for (size_t p = 0; p + pixel <= data.size(); p += pixel)
        for (size_t k = 0; k < sample; ++k) std::swap(data[p + k], data[p + 2 * sample + k]);
}

std::vector<uint8_t> encode_png(const StoredImage& im, const std::string& path) {
    if (im.width <= 0 || im.height <= 0) fail(path, "cannot write an empty image");
    if (im.channels < 1 || im.channels > 4 || (im.bits != 8 && im.bits != 16))
        fail(path, "a PNG holds 1-4 channels of 8 or 16 bits, not " + std::to_string(im.channels) + " of " +
                       std::to_string(im.bits));
    if (im.data.size() != im.row_bytes() * size_t(im.height)) fail(path, "the pixel buffer does not match the image size");
    static const int kType[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
    std::vector<uint8_t> out;
    std::vector<png_bytep> rows(size_t(im.height));
    for (int y = 0; y < im.height; ++y)
        rows[size_t(y)] = const_cast<png_bytep>(im.data.data() + size_t(y) * im.row_bytes());
    PngIo io;
    io.out = &out;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, png_on_error, png_on_warning);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, info ? &info : nullptr);
        fail(path, std::string("PNG encoding failed (") + io.message + ")");
    }
    png_set_write_fn(png, &io, png_write_bytes, png_flush);
    png_set_compression_level(png, 1);  // frames by the thousand: speed over a few per cent of size, as OpenCV
    png_set_IHDR(png, info, png_uint_32(im.width), png_uint_32(im.height), im.bits, kType[im.channels - 1],
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    if (im.bits == 16 && host_little_endian()) png_set_swap(png);
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return out;
}

}  // namespace vtloc::io
