/* cli.c — one command-line parser for every program, so that all of them treat flags alike
 * (see core.h, COMMAND LINES). */
#include "core.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *option_kind_metavar(const core_option *option) {
    if (option->metavar) return option->metavar;
    switch (option->kind) {
    case CORE_OPTION_INT: return "N";
    case CORE_OPTION_DOUBLE: return "X";
    case CORE_OPTION_STRING: return "VALUE";
    default: return "";
    }
}

void core_cli_print_usage(const core_cli *cli, void *file) {
    FILE *out = file;
    fprintf(out, "usage: %s [options]", cli->program);
    if (cli->positional_name)
        fprintf(out, cli->positional_min > 0 ? " %s" : " [%s]", cli->positional_name);
    fprintf(out, "\n");
    if (cli->summary) fprintf(out, "%s\n", cli->summary);
    fprintf(out, "\noptions:\n");
    for (int i = 0; i < cli->option_count; i++) {
        const core_option *option = &cli->options[i];
        char left[64];
        if (option->kind == CORE_OPTION_FLAG)
            snprintf(left, sizeof left, "--%s", option->name);
        else
            snprintf(left, sizeof left, "--%s %s", option->name, option_kind_metavar(option));
        fprintf(out, "  %-24s %s\n", left, option->help ? option->help : "");
    }
    fprintf(out, "  %-24s %s\n", "--help", "print this and exit");
}

static int usage_error(const core_cli *cli, const char *fmt, const char *what, const char *detail) {
    fprintf(stderr, "%s: ", cli->program);
    fprintf(stderr, fmt, what, detail);
    fprintf(stderr, "\n\n");
    core_cli_print_usage(cli, stderr);
    return CORE_CLI_ERROR;
}

static const core_option *find_option(const core_cli *cli, const char *name, size_t length) {
    for (int i = 0; i < cli->option_count; i++) {
        const char *candidate = cli->options[i].name;
        if (strlen(candidate) == length && strncmp(candidate, name, length) == 0)
            return &cli->options[i];
    }
    return NULL;
}

/* Stores `text` into the option's value; returns false when it is not a valid value. */
static bool store_value(const core_option *option, const char *text, const char **why) {
    char *end = NULL;
    errno = 0;
    switch (option->kind) {
    case CORE_OPTION_INT: {
        long value = strtol(text, &end, 10);
        if (*text == '\0' || *end != '\0' || errno) { *why = "is not a whole number"; return false; }
        bool bounded = option->min != 0 || option->max != 0;
        if (bounded && (value < option->min || value > option->max)) { *why = "is out of range"; return false; }
        if (!bounded && (value < -2147483647L - 1 || value > 2147483647L)) { *why = "is out of range"; return false; }
        *(int *)option->value = (int)value;
        return true;
    }
    case CORE_OPTION_DOUBLE: {
        double value = strtod(text, &end);
        if (*text == '\0' || *end != '\0' || errno || !isfinite(value)) { *why = "is not a number"; return false; }
        bool bounded = option->min_double != 0 || option->max_double != 0;
        if (bounded && (value < option->min_double || value > option->max_double)) { *why = "is out of range"; return false; }
        *(double *)option->value = value;
        return true;
    }
    case CORE_OPTION_STRING:
        if (*text == '\0') { *why = "is empty"; return false; }
        *(const char **)option->value = text;
        return true;
    default:
        *why = "takes no value";
        return false;
    }
}

static void describe_range(const core_option *option, char *buffer, size_t size) {
    buffer[0] = '\0';
    if (option->kind == CORE_OPTION_INT && (option->min || option->max))
        snprintf(buffer, size, " (expected %d to %d)", option->min, option->max);
    else if (option->kind == CORE_OPTION_DOUBLE && (option->min_double || option->max_double))
        snprintf(buffer, size, " (expected %g to %g)", option->min_double, option->max_double);
}

static int parse_option(const core_cli *cli, int argc, char **argv, int *index) {
    const char *arg = argv[*index] + 2;
    const char *equals = strchr(arg, '=');
    size_t name_length = equals ? (size_t)(equals - arg) : strlen(arg);
    const core_option *option = find_option(cli, arg, name_length);
    if (!option) return usage_error(cli, "unknown option '%s'%s", argv[*index], "");

    if (option->kind == CORE_OPTION_FLAG) {
        if (equals) return usage_error(cli, "option '--%s' takes no value%s", option->name, "");
        *(bool *)option->value = true;
        return CORE_CLI_OK;
    }
    const char *text = equals ? equals + 1 : NULL;
    if (!text) {
        if (*index + 1 >= argc) return usage_error(cli, "option '--%s' needs a value%s", option->name, "");
        text = argv[++*index];
    }
    const char *why = "";
    if (!store_value(option, text, &why)) {
        char range[96], detail[160];
        describe_range(option, range, sizeof range);
        snprintf(detail, sizeof detail, "'%s' %s%s", text, why, range);
        return usage_error(cli, "bad value for '--%s': %s", option->name, detail);
    }
    return CORE_CLI_OK;
}

int core_cli_parse(const core_cli *cli, int argc, char **argv) {
    int positional_count = 0;
    bool options_done = false;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!options_done && strcmp(arg, "--") == 0) { options_done = true; continue; }
        if (!options_done && (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0)) {
            core_cli_print_usage(cli, stdout);
            return CORE_CLI_HELP;
        }
        if (!options_done && arg[0] == '-' && arg[1] == '-') {
            int rc = parse_option(cli, argc, argv, &i);
            if (rc != CORE_CLI_OK) return rc;
            continue;
        }
        if (!options_done && arg[0] == '-' && arg[1] != '\0')
            return usage_error(cli, "unknown option '%s'%s", arg, "");
        if (!cli->positional_name || positional_count >= cli->positional_max)
            return usage_error(cli, "unexpected argument '%s'%s", arg, "");
        cli->positional[positional_count++] = arg;
    }
    if (cli->positional_name && positional_count < cli->positional_min)
        return usage_error(cli, "missing %s%s", cli->positional_name, "");
    if (cli->positional_count) *cli->positional_count = positional_count;
    return CORE_CLI_OK;
}
