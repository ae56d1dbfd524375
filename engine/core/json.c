/* json.c — a JSON (RFC 8259) parser into a DOM allocated from an arena, and a string writer
 * (see core.h, JSON).
 *
 * The parser is recursive descent over a byte buffer with an explicit size: it never reads past
 * `size`, never needs a terminating NUL, and stops at CORE_JSON_MAX_DEPTH nested containers so
 * hostile input cannot exhaust the stack. Containers are stored as contiguous arrays: while a
 * container is open its children wait on a scratch stack shared by all levels, and when it closes
 * they are copied to the arena in one piece (so no size has to be guessed up front).
 */
#include "core.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct json_parser {
    const char *text;
    size_t size;
    size_t pos;
    core_arena *arena;
    core_error *error;
    bool failed;
    int depth;
    /* Children of the open containers, innermost last. Keys only grow for objects. */
    core_json_value *values;
    size_t value_count, value_capacity;
    core_json_string *keys;
    size_t key_count, key_capacity;
} json_parser;

static bool json_parse_value(json_parser *p, core_json_value *out);

/* ---- errors ----------------------------------------------------------------------------- */

/* Records the first error, placed at byte offset `at`. Lines and columns count from 1; a column
 * counts characters (UTF-8 sequences), not bytes, so it matches what an editor shows. */
CORE_PRINTF(3, 4)
static bool json_fail_at(json_parser *p, size_t at, const char *fmt, ...) {
    if (p->failed) return false;
    p->failed = true;
    if (!p->error) return false;
    int line = 1, column = 1;
    for (size_t i = 0; i < at && i < p->size; i++) {
        unsigned char c = (unsigned char)p->text[i];
        if (c == '\n') {
            line++;
            column = 1;
        } else if ((c & 0xc0) != 0x80) {
            column++;
        }
    }
    char reason[160]; /* leaves room for the position in core_error's message[256] */
    va_list args;
    va_start(args, fmt);
    vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    return core_error_set(p->error, CORE_ERROR_FORMAT, "line %d, column %d: %s", line, column, reason);
}

/* Describes the byte at `at` for a message: a printable character in quotes, else its code. */
static const char *json_describe_byte(const json_parser *p, size_t at, char buffer[16]) {
    if (at >= p->size) return "end of input";
    unsigned char c = (unsigned char)p->text[at];
    if (c >= 0x20 && c < 0x7f) snprintf(buffer, 16, "'%c'", c);
    else snprintf(buffer, 16, "byte 0x%02x", c);
    return buffer;
}

/* ---- scratch stacks --------------------------------------------------------------------- */

static void json_push_value(json_parser *p, const core_json_value *value) {
    p->values = core_grow(p->values, &p->value_capacity, p->value_count + 1, sizeof *p->values);
    p->values[p->value_count++] = *value;
}

static void json_push_key(json_parser *p, core_json_string key) {
    p->keys = core_grow(p->keys, &p->key_capacity, p->key_count + 1, sizeof *p->keys);
    p->keys[p->key_count++] = key;
}

/* Moves the scratch entries from `first` on into the arena and pops them. */
static void *json_pop_to_arena(json_parser *p, void *items, size_t item_size, size_t first,
                               size_t *count) {
    size_t n = *count - first;
    *count = first;
    if (n == 0) return NULL;
    void *copy = core_arena_alloc(p->arena, n * item_size, alignof(max_align_t));
    return memcpy(copy, (char *)items + first * item_size, n * item_size);
}

/* ---- lexing helpers --------------------------------------------------------------------- */

static void json_skip_whitespace(json_parser *p) {
    while (p->pos < p->size) {
        char c = p->text[p->pos];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r') break;
        p->pos++;
    }
}

static int json_peek(const json_parser *p) {
    return p->pos < p->size ? (unsigned char)p->text[p->pos] : -1;
}

static bool json_is_digit(int c) { return c >= '0' && c <= '9'; }

/* Decodes one UTF-8 sequence; returns its length, or 0 when it is malformed (truncated, overlong,
 * a surrogate, or beyond U+10FFFF). Shared by the parser and the writer. */
static size_t json_decode_utf8(const unsigned char *s, size_t available, uint32_t *code_point) {
    unsigned char lead = s[0];
    size_t length;
    uint32_t cp, minimum;
    if (lead < 0x80) {
        *code_point = lead;
        return 1;
    } else if ((lead & 0xe0) == 0xc0) {
        length = 2, cp = lead & 0x1fu, minimum = 0x80;
    } else if ((lead & 0xf0) == 0xe0) {
        length = 3, cp = lead & 0x0fu, minimum = 0x800;
    } else if ((lead & 0xf8) == 0xf0) {
        length = 4, cp = lead & 0x07u, minimum = 0x10000;
    } else {
        return 0;
    }
    if (length > available) return 0;
    for (size_t i = 1; i < length; i++) {
        if ((s[i] & 0xc0) != 0x80) return 0;
        cp = (cp << 6) | (s[i] & 0x3fu);
    }
    if (cp < minimum || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return 0;
    *code_point = cp;
    return length;
}

static size_t json_encode_utf8(uint32_t cp, char *out) {
    if (cp < 0x80) {
        out[0] = (char)cp;
        return 1;
    } else if (cp < 0x800) {
        out[0] = (char)(0xc0 | (cp >> 6));
        out[1] = (char)(0x80 | (cp & 0x3f));
        return 2;
    } else if (cp < 0x10000) {
        out[0] = (char)(0xe0 | (cp >> 12));
        out[1] = (char)(0x80 | ((cp >> 6) & 0x3f));
        out[2] = (char)(0x80 | (cp & 0x3f));
        return 3;
    }
    out[0] = (char)(0xf0 | (cp >> 18));
    out[1] = (char)(0x80 | ((cp >> 12) & 0x3f));
    out[2] = (char)(0x80 | ((cp >> 6) & 0x3f));
    out[3] = (char)(0x80 | (cp & 0x3f));
    return 4;
}

/* ---- strings ---------------------------------------------------------------------------- */

/* Reads the 4 hex digits of a \u escape starting at `at`; -1 when they are not there. */
static long json_read_hex4(const json_parser *p, size_t at) {
    if (at > p->size || p->size - at < 4) return -1;
    long value = 0;
    for (size_t i = 0; i < 4; i++) {
        char c = p->text[at + i];
        int digit = c >= '0' && c <= '9'   ? c - '0'
                    : c >= 'a' && c <= 'f' ? c - 'a' + 10
                    : c >= 'A' && c <= 'F' ? c - 'A' + 10
                                           : -1;
        if (digit < 0) return -1;
        value = value * 16 + digit;
    }
    return value;
}

/* Decodes the \u escape at p->pos (pointing at the backslash), joining a surrogate pair. */
static bool json_read_unicode_escape(json_parser *p, uint32_t *code_point) {
    size_t start = p->pos;
    long unit = json_read_hex4(p, start + 2);
    if (unit < 0) return json_fail_at(p, start, "invalid \\u escape: expected 4 hex digits");
    p->pos = start + 6;
    if (unit >= 0xdc00 && unit <= 0xdfff)
        return json_fail_at(p, start, "unpaired surrogate \\u%04lX", unit);
    if (unit < 0xd800 || unit > 0xdbff) {
        *code_point = (uint32_t)unit;
        return true;
    }
    /* A high surrogate: UTF-16 needs the low half right after it to name a code point. */
    long low = -1;
    if (p->size - p->pos >= 6 && p->text[p->pos] == '\\' && p->text[p->pos + 1] == 'u')
        low = json_read_hex4(p, p->pos + 2);
    if (low < 0xdc00 || low > 0xdfff)
        return json_fail_at(p, start, "unpaired surrogate \\u%04lX", unit);
    p->pos += 6;
    *code_point = 0x10000 + (((uint32_t)unit - 0xd800) << 10) + ((uint32_t)low - 0xdc00);
    return true;
}

/* Finds the closing quote of the string opening at p->pos; returns its offset or 0 when the
 * input ends first. Escapes are only skipped here; json_parse_string checks them. */
static size_t json_find_string_end(const json_parser *p) {
    for (size_t i = p->pos + 1; i < p->size; i++) {
        if (p->text[i] == '\\') i++;
        else if (p->text[i] == '"') return i;
    }
    return 0;
}

static bool json_parse_escape(json_parser *p, char *out, size_t *length) {
    size_t at = p->pos;
    char c = at + 1 < p->size ? p->text[at + 1] : '\0';
    const char *simple = strchr("\"\\/bfnrt", c);
    if (c != '\0' && simple) {
        static const char decoded[] = "\"\\/\b\f\n\r\t";
        out[(*length)++] = decoded[simple - "\"\\/bfnrt"];
        p->pos += 2;
        return true;
    }
    if (c == 'u') {
        uint32_t cp = 0;
        if (!json_read_unicode_escape(p, &cp)) return false;
        *length += json_encode_utf8(cp, out + *length);
        return true;
    }
    char described[16];
    return json_fail_at(p, at, "invalid escape '\\' followed by %s",
                        json_describe_byte(p, at + 1, described));
}

/* Parses the string opening at p->pos. The decoded text is never longer than the raw text (each
 * escape shrinks or keeps its length), so one arena block of the raw length holds it. */
static bool json_parse_string(json_parser *p, core_json_string *out) {
    size_t open = p->pos;
    size_t close = json_find_string_end(p);
    if (close == 0) return json_fail_at(p, open, "unterminated string");
    char *chars = core_arena_alloc(p->arena, close - open, 1);
    size_t length = 0;
    p->pos = open + 1;
    while (p->pos < close) {
        unsigned char c = (unsigned char)p->text[p->pos];
        if (c == '\\') {
            if (!json_parse_escape(p, chars, &length)) return false;
        } else if (c < 0x20) {
            return json_fail_at(p, p->pos, "control character 0x%02x in string (escape it)", c);
        } else if (c < 0x80) {
            chars[length++] = (char)c;
            p->pos++;
        } else {
            uint32_t cp;
            size_t n = json_decode_utf8((const unsigned char *)p->text + p->pos, close - p->pos, &cp);
            if (n == 0) return json_fail_at(p, p->pos, "invalid UTF-8 in string");
            memcpy(chars + length, p->text + p->pos, n);
            length += n;
            p->pos += n;
        }
    }
    chars[length] = '\0';
    p->pos = close + 1;
    *out = (core_json_string){ .chars = chars, .length = length };
    return true;
}

/* ---- numbers and literals --------------------------------------------------------------- */

static size_t json_skip_digits(json_parser *p) {
    size_t start = p->pos;
    while (json_is_digit(json_peek(p))) p->pos++;
    return p->pos - start;
}

/* Checks the RFC 8259 number grammar, then converts with strtod, which rounds correctly. */
static bool json_parse_number(json_parser *p, core_json_value *out) {
    size_t start = p->pos;
    if (json_peek(p) == '-') p->pos++;
    if (json_peek(p) == '0') {
        p->pos++;
        if (json_is_digit(json_peek(p)))
            return json_fail_at(p, start, "leading zeros are not allowed in numbers");
    } else if (json_skip_digits(p) == 0) {
        return json_fail_at(p, p->pos, "expected a digit");
    }
    if (json_peek(p) == '.') {
        p->pos++;
        if (json_skip_digits(p) == 0) return json_fail_at(p, p->pos, "expected a digit after '.'");
    }
    if (json_peek(p) == 'e' || json_peek(p) == 'E') {
        p->pos++;
        if (json_peek(p) == '+' || json_peek(p) == '-') p->pos++;
        if (json_skip_digits(p) == 0)
            return json_fail_at(p, p->pos, "expected a digit in the exponent");
    }
    /* strtod needs a NUL-terminated copy; the input may end right after the number. */
    size_t length = p->pos - start;
    char small[64];
    char *copy = length < sizeof small ? small : core_alloc(length + 1);
    memcpy(copy, p->text + start, length);
    copy[length] = '\0';
    double value = strtod(copy, NULL);
    if (copy != small) core_free(copy, length + 1);
    if (isinf(value)) return json_fail_at(p, start, "number out of range");
    *out = (core_json_value){ .type = CORE_JSON_NUMBER, .number = value };
    return true;
}

static bool json_match_word(json_parser *p, const char *word) {
    size_t length = strlen(word);
    if (p->size - p->pos < length || memcmp(p->text + p->pos, word, length) != 0) return false;
    p->pos += length;
    return true;
}

static bool json_parse_literal(json_parser *p, core_json_value *out) {
    if (json_match_word(p, "true")) *out = (core_json_value){ .type = CORE_JSON_BOOL, .boolean = true };
    else if (json_match_word(p, "false")) *out = (core_json_value){ .type = CORE_JSON_BOOL };
    else if (json_match_word(p, "null")) *out = (core_json_value){ .type = CORE_JSON_NULL };
    else return json_fail_at(p, p->pos, "invalid literal (expected true, false or null)");
    return true;
}

/* ---- containers ------------------------------------------------------------------------- */

static bool json_enter(json_parser *p) {
    if (++p->depth > CORE_JSON_MAX_DEPTH)
        return json_fail_at(p, p->pos, "nesting deeper than %d levels", CORE_JSON_MAX_DEPTH);
    p->pos++; /* the opening bracket */
    json_skip_whitespace(p);
    return true;
}

static bool json_parse_array(json_parser *p, core_json_value *out) {
    if (!json_enter(p)) return false;
    size_t first = p->value_count;
    if (json_peek(p) != ']') {
        for (;;) {
            core_json_value item;
            if (!json_parse_value(p, &item)) return false;
            json_push_value(p, &item);
            json_skip_whitespace(p);
            if (json_peek(p) == ']') break;
            if (json_peek(p) != ',') return json_fail_at(p, p->pos, "expected ',' or ']' in array");
            p->pos++;
            json_skip_whitespace(p);
            if (json_peek(p) == ']') return json_fail_at(p, p->pos, "trailing ',' before ']'");
        }
    }
    p->pos++;
    p->depth--;
    out->type = CORE_JSON_ARRAY;
    out->array.count = p->value_count - first;
    out->array.items = json_pop_to_arena(p, p->values, sizeof *p->values, first, &p->value_count);
    return true;
}

static bool json_parse_member(json_parser *p) {
    if (json_peek(p) != '"') return json_fail_at(p, p->pos, "expected a string key");
    core_json_string key;
    if (!json_parse_string(p, &key)) return false;
    json_skip_whitespace(p);
    if (json_peek(p) != ':') return json_fail_at(p, p->pos, "expected ':' after object key");
    p->pos++;
    core_json_value value;
    if (!json_parse_value(p, &value)) return false;
    json_push_key(p, key);
    json_push_value(p, &value);
    return true;
}

static bool json_parse_object(json_parser *p, core_json_value *out) {
    if (!json_enter(p)) return false;
    size_t first_value = p->value_count, first_key = p->key_count;
    if (json_peek(p) != '}') {
        for (;;) {
            if (!json_parse_member(p)) return false;
            json_skip_whitespace(p);
            if (json_peek(p) == '}') break;
            if (json_peek(p) != ',') return json_fail_at(p, p->pos, "expected ',' or '}' in object");
            p->pos++;
            json_skip_whitespace(p);
            if (json_peek(p) == '}') return json_fail_at(p, p->pos, "trailing ',' before '}'");
        }
    }
    p->pos++;
    p->depth--;
    out->type = CORE_JSON_OBJECT;
    out->object.count = p->value_count - first_value;
    out->object.values =
        json_pop_to_arena(p, p->values, sizeof *p->values, first_value, &p->value_count);
    out->object.keys = json_pop_to_arena(p, p->keys, sizeof *p->keys, first_key, &p->key_count);
    return true;
}

static bool json_parse_value(json_parser *p, core_json_value *out) {
    json_skip_whitespace(p);
    int c = json_peek(p);
    if (c == '{') return json_parse_object(p, out);
    if (c == '[') return json_parse_array(p, out);
    if (c == '"') {
        out->type = CORE_JSON_STRING;
        return json_parse_string(p, &out->string);
    }
    if (c == '-' || json_is_digit(c)) return json_parse_number(p, out);
    if (c == 't' || c == 'f' || c == 'n') return json_parse_literal(p, out);
    if (c < 0) return json_fail_at(p, p->pos, "expected a value, found end of input");
    char described[16];
    return json_fail_at(p, p->pos, "expected a value, found %s", json_describe_byte(p, p->pos, described));
}

/* ---- public API ------------------------------------------------------------------------- */

bool core_json_parse(const char *text, size_t size, core_arena *arena, core_json_value **out,
                     core_error *error) {
    json_parser p = { .text = text, .size = text ? size : 0, .arena = arena, .error = error };
    *out = NULL;
    /* A UTF-8 byte-order mark is not JSON, but editors add it; RFC 8259 lets parsers skip it. */
    if (p.size >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0) p.pos = 3;
    core_json_value root;
    bool ok = json_parse_value(&p, &root);
    if (ok) {
        json_skip_whitespace(&p);
        if (p.pos < p.size) ok = json_fail_at(&p, p.pos, "unexpected text after the JSON value");
    }
    if (ok) {
        *out = core_arena_alloc(arena, sizeof root, alignof(core_json_value));
        **out = root;
    }
    core_free(p.values, p.value_capacity * sizeof *p.values);
    core_free(p.keys, p.key_capacity * sizeof *p.keys);
    return ok;
}

const core_json_value *core_json_get(const core_json_value *object, const char *key) {
    if (!object || object->type != CORE_JSON_OBJECT) return NULL;
    size_t length = strlen(key);
    /* The last duplicate wins, as in JavaScript: RFC 8259 leaves duplicates to the reader. */
    for (size_t i = object->object.count; i-- > 0;) {
        const core_json_string *k = &object->object.keys[i];
        if (k->length == length && memcmp(k->chars, key, length) == 0) return &object->object.values[i];
    }
    return NULL;
}

double core_json_number_or(const core_json_value *value, double fallback) {
    return value && value->type == CORE_JSON_NUMBER ? value->number : fallback;
}

const char *core_json_string_or(const core_json_value *value, const char *fallback) {
    return value && value->type == CORE_JSON_STRING ? value->string.chars : fallback;
}

bool core_json_string_equals(const core_json_value *value, const char *text) {
    if (!value || value->type != CORE_JSON_STRING) return false;
    size_t length = strlen(text);
    return value->string.length == length && memcmp(value->string.chars, text, length) == 0;
}

/* ---- writer ----------------------------------------------------------------------------- */

/* The escape for one byte that JSON does not allow raw in a string, or NULL for a plain one. */
static const char *json_escape_for(unsigned char c, char buffer[8]) {
    switch (c) {
    case '"': return "\\\"";
    case '\\': return "\\\\";
    case '\n': return "\\n";
    case '\r': return "\\r";
    case '\t': return "\\t";
    case '\b': return "\\b";
    case '\f': return "\\f";
    default:
        if (c >= 0x20) return NULL;
        snprintf(buffer, 8, "\\u%04x", c);
        return buffer;
    }
}

void core_json_write_string(void *file, const char *s) {
    FILE *out = file;
    const unsigned char *bytes = (const unsigned char *)(s ? s : "");
    size_t length = strlen((const char *)bytes);
    size_t run = 0; /* start of the bytes not yet written */
    fputc('"', out);
    for (size_t i = 0; i < length;) {
        char buffer[8];
        const char *escape = bytes[i] < 0x80 ? json_escape_for(bytes[i], buffer) : NULL;
        size_t n = 1;
        uint32_t cp;
        /* Invalid UTF-8 would make the whole file invalid JSON; write U+FFFD in its place. */
        if (bytes[i] >= 0x80 && (n = json_decode_utf8(bytes + i, length - i, &cp)) == 0) {
            escape = "\\ufffd";
            n = 1;
        }
        if (escape) {
            fwrite(bytes + run, 1, i - run, out);
            fputs(escape, out);
            run = i + n;
        }
        i += n;
    }
    fwrite(bytes + run, 1, length - run, out);
    fputc('"', out);
}
