/* Tests of the JSON parser and string writer (engine/core/json.c). Every expected value, line
 * and column below was worked out by hand from RFC 8259 and the input text. */
#include "core/core.h"

#include "test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Parses a C string; the arena is released by the caller. */
static core_json_value *parse_ok(core_arena *arena, const char *text) {
    core_json_value *root = NULL;
    core_error error = { 0 };
    bool ok = core_json_parse(text, strlen(text), arena, &root, &error);
    cr_assert(ok, "parsing %s failed: %s", text, error.message);
    cr_assert_not_null(root);
    return root;
}

/* Parses text that must fail, and checks where and why. */
static void expect_error(const char *text, size_t size, int line, int column, const char *reason) {
    core_arena arena = { 0 };
    static core_json_value sentinel;
    core_json_value *root = &sentinel; /* must be reset to NULL */
    core_error error = { 0 };
    bool ok = core_json_parse(text, size, &arena, &root, &error);
    core_arena_release(&arena);
    cr_assert_not(ok, "%s parsed but should not", text);
    cr_expect_null(root);
    cr_expect_eq(error.code, CORE_ERROR_FORMAT, "%s: code %s", text, core_error_code_name(error.code));
    /* The position is part of the message: that is what a person reads. */
    int got_line = 0, got_column = 0;
    cr_assert_eq(sscanf(error.message, "line %d, column %d:", &got_line, &got_column), 2, "%s", error.message);
    cr_expect_eq(got_line, line, "%s: line %d, expected %d (%s)", text, got_line, line, error.message);
    cr_expect_eq(got_column, column, "%s: column %d, expected %d (%s)", text, got_column, column, error.message);
    char expected[256];
    snprintf(expected, sizeof expected, "line %d, column %d: %s", line, column, reason);
    cr_expect_str_eq(error.message, expected);
}

static void expect_error_text(const char *text, int line, int column, const char *reason) {
    expect_error(text, strlen(text), line, column, reason);
}

/* ---- valid documents -------------------------------------------------------------------- */

Test(core_json, scalars) {
    core_arena arena = { 0 };
    core_json_value *v = parse_ok(&arena, "true");
    cr_expect_eq(v->type, CORE_JSON_BOOL);
    cr_expect(v->boolean);
    v = parse_ok(&arena, " false ");
    cr_expect_eq(v->type, CORE_JSON_BOOL);
    cr_expect_not(v->boolean);
    v = parse_ok(&arena, "\n\tnull\r\n");
    cr_expect_eq(v->type, CORE_JSON_NULL);
    v = parse_ok(&arena, "\"\"");
    cr_expect_eq(v->type, CORE_JSON_STRING);
    cr_expect_eq(v->string.length, 0);
    cr_expect_str_eq(v->string.chars, "");
    core_arena_release(&arena);
}

Test(core_json, numbers) {
    core_arena arena = { 0 };
    /* -0.5e2 = -0.5 · 100 = -50; 1E+2 = 100; 25e-2 = 0.25; all exact in binary. */
    struct { const char *text; double value; } cases[] = {
        { "0", 0.0 },        { "-0", -0.0 },         { "7", 7.0 },    { "-0.5e2", -50.0 },
        { "1E+2", 100.0 },   { "25e-2", 0.25 },      { "123.456", 123.456 },
        { "9007199254740993", 9007199254740992.0 },  /* 2^53 + 1 rounds to even: 2^53 */
        { "1e-400", 0.0 },                           /* underflow is a tiny number: 0 */
    };
    for (size_t i = 0; i < CORE_COUNTOF(cases); i++) {
        core_json_value *v = parse_ok(&arena, cases[i].text);
        cr_expect_eq(v->type, CORE_JSON_NUMBER, "%s", cases[i].text);
        cr_expect(v->number == cases[i].value, "%s gave %.17g", cases[i].text, v->number);
    }
    core_arena_release(&arena);
}

Test(core_json, objects_and_arrays) {
    core_arena arena = { 0 };
    core_json_value *root = parse_ok(&arena, "{\"a\": [1, 2, {\"b\": null}], \"c\": \"x\", \"e\": {}, \"f\": []}");
    cr_assert_eq(root->type, CORE_JSON_OBJECT);
    cr_assert_eq(root->object.count, 4);
    cr_expect_str_eq(root->object.keys[0].chars, "a");
    cr_expect_str_eq(root->object.keys[3].chars, "f");

    const core_json_value *a = core_json_get(root, "a");
    cr_assert_not_null(a);
    cr_assert_eq(a->type, CORE_JSON_ARRAY);
    cr_assert_eq(a->array.count, 3);
    cr_expect(a->array.items[0].number == 1.0);
    cr_expect(a->array.items[1].number == 2.0);
    const core_json_value *b = core_json_get(&a->array.items[2], "b");
    cr_assert_not_null(b);
    cr_expect_eq(b->type, CORE_JSON_NULL);

    cr_expect(core_json_string_equals(core_json_get(root, "c"), "x"));
    cr_expect_eq(core_json_get(root, "e")->object.count, 0);
    cr_expect_eq(core_json_get(root, "f")->array.count, 0);
    cr_expect_null(core_json_get(root, "missing"));
    cr_expect_null(core_json_get(a, "a")); /* not an object */
    cr_expect_null(core_json_get(NULL, "a"));
    core_arena_release(&arena);
}

Test(core_json, duplicate_keys_last_wins) {
    core_arena arena = { 0 };
    core_json_value *root = parse_ok(&arena, "{\"k\": 1, \"k\": 2}");
    cr_expect_eq(root->object.count, 2);
    cr_expect(core_json_number_or(core_json_get(root, "k"), 0) == 2.0);
    core_arena_release(&arena);
}

Test(core_json, helpers_fall_back_on_other_types) {
    core_arena arena = { 0 };
    core_json_value *root = parse_ok(&arena, "{\"n\": 3.5, \"s\": \"hi\"}");
    cr_expect(core_json_number_or(core_json_get(root, "n"), -1) == 3.5);
    cr_expect(core_json_number_or(core_json_get(root, "s"), -1) == -1);
    cr_expect(core_json_number_or(NULL, -1) == -1);
    cr_expect_str_eq(core_json_string_or(core_json_get(root, "s"), "?"), "hi");
    cr_expect_str_eq(core_json_string_or(core_json_get(root, "n"), "?"), "?");
    cr_expect_not(core_json_string_equals(core_json_get(root, "s"), "h"));
    cr_expect_not(core_json_string_equals(core_json_get(root, "n"), "3.5"));
    core_arena_release(&arena);
}

Test(core_json, string_escapes) {
    core_arena arena = { 0 };
    /* The eight two-character escapes, each one byte once decoded. */
    core_json_value *v = parse_ok(&arena, "\"\\\"\\\\\\/\\b\\f\\n\\r\\t\"");
    cr_expect_eq(v->string.length, 8);
    cr_expect_str_eq(v->string.chars, "\"\\/\b\f\n\r\t");

    /* U+00E9 é = C3 A9; U+20AC € = E2 82 AC (hex digits in either case). */
    v = parse_ok(&arena, "\"\\u00e9\\u20AC\"");
    cr_expect_str_eq(v->string.chars, "\xc3\xa9\xe2\x82\xac");

    /* D83D DE00: 0x10000 + (0x3D << 10) + 0x200 = U+1F600, UTF-8 F0 9F 98 80. */
    v = parse_ok(&arena, "\"<\\uD83D\\uDE00>\"");
    cr_expect_str_eq(v->string.chars, "<\xf0\x9f\x98\x80>");
    cr_expect_eq(v->string.length, 6);

    /* \u0000 puts a NUL inside: length says 3, strlen would say 1. */
    v = parse_ok(&arena, "\"a\\u0000b\"");
    cr_expect_eq(v->string.length, 3);
    cr_expect(memcmp(v->string.chars, "a\0b", 3) == 0);

    /* Raw UTF-8 passes through unchanged. */
    v = parse_ok(&arena, "\"caf\xc3\xa9 \xf0\x9f\x98\x80\"");
    cr_expect_str_eq(v->string.chars, "caf\xc3\xa9 \xf0\x9f\x98\x80");
    core_arena_release(&arena);
}

Test(core_json, byte_order_mark_is_skipped) {
    core_arena arena = { 0 };
    core_json_value *v = parse_ok(&arena, "\xef\xbb\xbf[1]");
    cr_expect_eq(v->array.count, 1);
    core_arena_release(&arena);
}

Test(core_json, size_bounds_the_input) {
    core_arena arena = { 0 };
    core_json_value *v;
    core_error error = { 0 };
    /* Only "12" of "123" is read. */
    cr_assert(core_json_parse("123", 2, &arena, &v, &error));
    cr_expect(v->number == 12.0);
    /* A heap buffer with no NUL after it: AddressSanitizer catches any read past the end. */
    const char text[] = "[1, \"ab";
    char *exact = malloc(sizeof text - 1);
    memcpy(exact, text, sizeof text - 1);
    cr_expect_not(core_json_parse(exact, sizeof text - 1, &arena, &v, &error));
    cr_expect_eq(error.code, CORE_ERROR_FORMAT);
    cr_expect_str_eq(error.message, "line 1, column 5: unterminated string");
    memcpy(exact, "[1, tr", 6);
    cr_expect_not(core_json_parse(exact, 6, &arena, &v, &error));
    cr_expect_str_eq(error.message, "line 1, column 5: invalid literal (expected true, false or null)");
    free(exact);
    core_arena_release(&arena);
}

Test(core_json, nesting_up_to_the_limit) {
    /* 256 '[' then 256 ']' is exactly the limit. */
    char text[2 * CORE_JSON_MAX_DEPTH + 1];
    memset(text, '[', CORE_JSON_MAX_DEPTH);
    memset(text + CORE_JSON_MAX_DEPTH, ']', CORE_JSON_MAX_DEPTH);
    text[2 * CORE_JSON_MAX_DEPTH] = '\0';
    core_arena arena = { 0 };
    core_json_value *v = parse_ok(&arena, text);
    int depth = 0;
    while (v->type == CORE_JSON_ARRAY && v->array.count == 1) v = &v->array.items[0], depth++;
    cr_expect_eq(depth, CORE_JSON_MAX_DEPTH - 1); /* the innermost array is empty */
    core_arena_release(&arena);
}

Test(core_json, nesting_past_the_limit_fails_without_recursing_further) {
    /* The 257th '[' (offset 256, column 257) is one level too deep. */
    size_t size = 100000;
    char *text = malloc(size);
    memset(text, '[', size);
    expect_error(text, size, 1, CORE_JSON_MAX_DEPTH + 1, "nesting deeper than 256 levels");
    memset(text, ' ', size);
    memcpy(text + size - 2, "{}", 2);
    core_arena arena = { 0 };
    core_json_value *v;
    cr_expect(core_json_parse(text, size, &arena, &v, NULL)); /* NULL error is allowed */
    core_arena_release(&arena);
    free(text);
}

/* ---- errors ----------------------------------------------------------------------------- */

Test(core_json, errors_name_line_and_column) {
    /* {"a" 1}: '{'=1 '"'=2 'a'=3 '"'=4 ' '=5 '1'=6. */
    expect_error_text("{\"a\" 1}", 1, 6, "expected ':' after object key");
    /* Line 3 is `    "dur" 12`: four spaces, "dur" at 5–9, a space at 10, '1' at 11. */
    expect_error_text("{\n  \"ts\": 1,\n    \"dur\" 12\n}", 3, 11, "expected ':' after object key");
    /* Whitespace only: the end is line 2, after two spaces, so column 3. */
    expect_error_text("   \n  ", 2, 3, "expected a value, found end of input");
    expect_error_text("", 1, 1, "expected a value, found end of input");
}

Test(core_json, errors_in_containers) {
    expect_error_text("[1, 2,]", 1, 7, "trailing ',' before ']'");
    expect_error_text("[1 2]", 1, 4, "expected ',' or ']' in array");
    expect_error_text("{\"a\":1,}", 1, 8, "trailing ',' before '}'");
    expect_error_text("{\"a\":1 \"b\":2}", 1, 8, "expected ',' or '}' in object");
    expect_error_text("{1:2}", 1, 2, "expected a string key");
    expect_error_text("[", 1, 2, "expected a value, found end of input");
    expect_error_text("{\"a\":1", 1, 7, "expected ',' or '}' in object");
    expect_error_text("{} x", 1, 4, "unexpected text after the JSON value");
    expect_error_text("]", 1, 1, "expected a value, found ']'");
    expect_error_text("\x01", 1, 1, "expected a value, found byte 0x01");
}

Test(core_json, errors_in_numbers_and_literals) {
    expect_error_text("01", 1, 1, "leading zeros are not allowed in numbers");
    expect_error_text("-", 1, 2, "expected a digit");
    expect_error_text("-x", 1, 2, "expected a digit");
    expect_error_text("1.", 1, 3, "expected a digit after '.'");
    expect_error_text("1.e5", 1, 3, "expected a digit after '.'");
    expect_error_text("1e", 1, 3, "expected a digit in the exponent");
    expect_error_text("1e+", 1, 4, "expected a digit in the exponent");
    expect_error_text("+1", 1, 1, "expected a value, found '+'");
    expect_error_text(".5", 1, 1, "expected a value, found '.'");
    expect_error_text("1e999", 1, 1, "number out of range");
    expect_error_text("tru", 1, 1, "invalid literal (expected true, false or null)");
    expect_error_text("nul", 1, 1, "invalid literal (expected true, false or null)");
    expect_error_text("True", 1, 1, "expected a value, found 'T'");
    expect_error_text("truex", 1, 5, "unexpected text after the JSON value");
}

Test(core_json, errors_in_strings) {
    expect_error_text("\"abc", 1, 1, "unterminated string");
    expect_error_text("\"abc\\\"", 1, 1, "unterminated string"); /* the last quote is escaped */
    expect_error_text("\"a\\qb\"", 1, 3, "invalid escape '\\' followed by 'q'");
    expect_error_text("\"\\u12G4\"", 1, 2, "invalid \\u escape: expected 4 hex digits");
    expect_error_text("\"\\u12\"", 1, 2, "invalid \\u escape: expected 4 hex digits");
    expect_error_text("\"\\uD800\"", 1, 2, "unpaired surrogate \\uD800");
    expect_error_text("\"\\uDC00\"", 1, 2, "unpaired surrogate \\uDC00");
    expect_error_text("\"\\uD800\\u0041\"", 1, 2, "unpaired surrogate \\uD800");
    expect_error_text("\"a\tb\"", 1, 3, "control character 0x09 in string (escape it)");
    expect_error_text("\"a\nb\"", 1, 3, "control character 0x0a in string (escape it)");
    expect_error_text("\"\xff\"", 1, 2, "invalid UTF-8 in string");
    expect_error_text("\"\xc0\xaf\"", 1, 2, "invalid UTF-8 in string");         /* overlong '/' */
    expect_error_text("\"\xed\xa0\x80\"", 1, 2, "invalid UTF-8 in string");     /* encoded surrogate */
    expect_error_text("\"\xf4\x90\x80\x80\"", 1, 2, "invalid UTF-8 in string"); /* U+110000 */
    expect_error_text("\"\xe2\x82\"", 1, 2, "invalid UTF-8 in string");         /* cut short */
}

Test(core_json, columns_count_characters_not_bytes) {
    /* ["é" x]: '['=1 '"'=2 'é'=3 (two bytes) '"'=4 ' '=5 'x'=6; bytes would say 7. */
    expect_error_text("[\"\xc3\xa9\" x]", 1, 6, "expected ',' or ']' in array");
}

/* ---- writer ----------------------------------------------------------------------------- */

static char *write_to_string(const char *s) {
    char *buffer = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&buffer, &size);
    core_json_write_string(out, s);
    fclose(out);
    return buffer;
}

Test(core_json, writer_escapes) {
    char *text = write_to_string("a\"b\\c\n\t\x01 caf\xc3\xa9");
    cr_expect_str_eq(text, "\"a\\\"b\\\\c\\n\\t\\u0001 caf\xc3\xa9\"");
    free(text);
    text = write_to_string("");
    cr_expect_str_eq(text, "\"\"");
    free(text);
}

Test(core_json, writer_replaces_invalid_utf8) {
    /* 0xFF can start no sequence; C3 followed by 'x' is cut short. */
    char *text = write_to_string("a\xff" "b\xc3x");
    cr_expect_str_eq(text, "\"a\\ufffdb\\ufffdx\"");
    free(text);
}

Test(core_json, writer_output_parses_back) {
    const char *original = "quote \" backslash \\ tab \t bell \x07 \xe2\x82\xac end";
    char *text = write_to_string(original);
    core_arena arena = { 0 };
    core_json_value *v = parse_ok(&arena, text);
    cr_expect_eq(v->type, CORE_JSON_STRING);
    cr_expect_str_eq(v->string.chars, original);
    core_arena_release(&arena);
    free(text);
}
