/* platform_host.c -- example_print() on a hosted system. */
#include <stdio.h>

void example_print(const char *s);
void example_print(const char *s) { (void)fputs(s, stdout); }
